// corrlap: command-line front end. Each subcommand lives in its own cmd_*.cpp file.
#include <unistd.h>

#include <algorithm>
#include <corrlap/backends/parallel.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <corrlap/core/threads.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <new>

#include "command.hpp"
#include "deprecated.hpp"
#include "validators.hpp"

namespace corrlap::cli {
std::vector<Command>& commands() {
  static std::vector<Command> list;
  return list;
}

namespace {

bool is_backend_option(const std::string& name) {
  for (const std::string& n : linear_solver_registry().names())
    for (const ParameterInfo& o : linear_solver_registry().create(n)->options())
      if (o.name == name) return true;
  for (const std::string& n : eigen_solver_registry().names())
    for (const ParameterInfo& o : eigen_solver_registry().create(n)->options())
      if (o.name == name) return true;
  return false;
}

// How the user gives the library parameter `parameter` to the command that ran: its flag when the
// command (or corrlap itself) has one, else a backend option through --solver-option.
std::string cli_spelling(const CLI::App& app, const std::string& parameter) {
  const std::string flag = flag_of(parameter);
  if (app.get_option_no_throw(flag)) return flag;
  for (const CLI::App* sub : app.get_subcommands()) {
    if (sub->get_option_no_throw(flag)) return flag;
    if (sub->get_option_no_throw("--solver-option") && is_backend_option(parameter))
      return "--solver-option " + parameter + "=...";
  }
  return {};
}

// The library speaks in parameter names; the CLI adds its own spelling of the one at fault.
void report(const CLI::App& app, const corrlap::Error& e) {
  std::cerr << "corrlap: error: " << e.what();
  if (const auto* input = dynamic_cast<const corrlap::InputError*>(&e); input && !input->parameter().empty())
    if (const std::string spelling = cli_spelling(app, input->parameter()); !spelling.empty())
      std::cerr << " (" << spelling << ")";
  std::cerr << "\n";
}

// Transparent huge pages for the allocator's memory, on request (CORRLAP_HUGE_PAGES=1, glibc >=
// 2.35: the tunable glibc.malloc.hugetlb=1 can only be set in the environment at process start, so
// the process starts itself again once with it). Not by default: on virtual machines that report
// free memory to the host (virtio-balloon's free page reporting), every fresh huge page is backed
// by the host again on first touch, and the factorizations' fresh arrays made regularize slower,
// not faster (bench/RESULTS.md, "Huge pages on a machine that reports free pages"). A
// GLIBC_TUNABLES of the user's own is left alone; where exec fails the run goes on as it is.
void use_huge_pages(char** argv) {
#if defined(__GLIBC__) && defined(__linux__)
  if (std::getenv("GLIBC_TUNABLES") != nullptr) return;
  if (const char* flag = std::getenv("CORRLAP_HUGE_PAGES"); flag == nullptr || std::string(flag) != "1") return;
  if (setenv("GLIBC_TUNABLES", "glibc.malloc.hugetlb=1", 1) != 0) return;
  execv("/proc/self/exe", argv);
  unsetenv("GLIBC_TUNABLES");
#else
  (void)argv;
#endif
}
}  // namespace
}  // namespace corrlap::cli

int main(int argc, char** argv) {
  using namespace corrlap;
  cli::use_huge_pages(argv);
  // Before any thread computes (core/threads.hpp says why).
  flush_subnormals_in_process();
  // Under mpirun every rank runs the command (the PETSc backends solve together); rank 0 alone
  // prints results. Errors and warnings (stderr) stay on every rank: any rank may be the one failing.
  if (!is_output_rank() && std::freopen("/dev/null", "w", stdout) == nullptr) return 2;
  CLI::App app{"corrlap: corrected Laplace-Beltrami operators for digital surfaces"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "corrlap 0.1.0");
  int threads = 0;
  app.add_option("--threads", threads, "worker threads for TBB and OpenBLAS (default: all; env CORRLAP_THREADS)")
      ->check(corrlap::cli::non_negative_number());
  std::string max_memory;
  app.add_option("--max-memory", max_memory,
                 "memory budget for what the input asks for (voxel grids, surfels, file contents), e.g. 8G or "
                 "512M; larger requests are refused before allocating (default: this machine's memory; env "
                 "CORRLAP_MAX_MEMORY)");
  auto& list = cli::commands();
  std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.order < b.order; });
  for (const auto& c : list) c.setup(app);
  app.parse_complete_callback([&] {
    try {
      if (threads > 0)
        set_thread_count(threads);
      else
        apply_thread_count_from_environment();
      if (!max_memory.empty())
        set_memory_budget(parse_memory_size(max_memory));
      else
        apply_memory_budget_from_environment();
    } catch (const corrlap::Error& e) {
      cli::report(app, e);
      std::exit(1);
    }
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::RequiredError& e) {
    // "A subcommand is required" also when the first word is a misspelt command: name it.
    for (const std::string& word : app.remaining()) {
      if (word.empty() || word[0] == '-') continue;
      std::string names;
      for (const auto& c : list) names += " " + c.name;
      std::cerr << "corrlap: error: unknown command '" << word << "'; commands:" << names << "\n";
      return 1;
    }
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const corrlap::Error& e) {
    cli::report(app, e);
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // A path the user gave cannot be used (a file where a folder is needed, no permission): the
    // user's to fix, not a bug. The message names the operation, the reason and the path.
    std::string what = e.what();
    if (const std::string prefix = "filesystem error: "; what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    std::cerr << "corrlap: error: " << what << "; check the path and its permissions\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "corrlap: error: out of memory\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "corrlap: internal error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

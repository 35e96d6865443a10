// corrlap study: the paper's evaluations (§3; docs/math.md §10) in one command: forward, backward and
// eigenvalue errors of several methods over grid steps and centres, and the cotan comparison on a
// triangle mesh (§3.4), written as CSV tables
// (results, summary, fitted orders) and plots (studies/plot_study.py). docs/studies.md.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/studies/regularization_study.hpp>
#include <corrlap/studies/study.hpp>
#include <corrlap/studies/study_index.hpp>
#include <corrlap/studies/study_tables.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "command.hpp"
#include "method_options.hpp"
#include "study_output.hpp"
#include "surface_source.hpp"
#include "validators.hpp"

namespace corrlap::cli {
namespace {

struct StudyArgs {
  std::string kind;
  std::string methods = "fem,interpolated,corrected-vrm,projected-polydec";
  std::string h = "0.1,0.05,0.025";
  std::string functions = "x2,expx,p6";
  std::string resolutions = "128,256,512";
  bool normals_given = false;
  StudyOptions options;
  double diffusion = kDefaultStudyDiffusion;  // StudyOptions::diffusion when --diffusion is given
  MethodOptions method_params;                // --param and the parameter flags, for the methods that declare them
  std::vector<double> bbox = {-2.0, 2.0};
  std::string out;
  bool resume = false, overwrite = false, no_plots = false;
  // The regularization study (paper Fig. 13 and 15)
  std::string shapes = "sphere1,torus,goursat";
  std::string alpha0 = "10";
  bool bbox_given = false;
  bool allow_nonmanifold = false;  // accepted and ignored (kAllowNonmanifoldNote)
  CLI::Option *h_option = nullptr, *resolutions_option = nullptr, *diffusion_option = nullptr;
  const CLI::App* command = nullptr;
};

// A study writes in place, so that the rows of an interrupted run stay for --resume; --overwrite
// builds the new study beside the old one, which it replaces only when it succeeds. Either way a
// failing run leaves no new file (OutputFolder).
OutputFolder::Mode study_output_mode(const StudyArgs& a) {
  return a.overwrite ? OutputFolder::Mode::Staged : OutputFolder::Mode::InPlace;
}

// The options a resumed study must share with the one in DIR (methods, h and functions may grow).
nlohmann::json fixed_options(const StudyOptions& o) {
  nlohmann::json j;
  j["study"] = to_string(o.kind);
  j["normals"] = o.normals;
  j["ii_k"] = o.ii_k;
  j["ii_alpha"] = o.ii_alpha;
  j["centers"] = o.centers;
  j["seed"] = o.seed;
  j["shape"] = o.shape;
  j["bbox"] = {o.min_aabb, o.max_aabb};
  j["offset"] = o.offset;
  j["diffusion"] = o.forward_diffusion();
  j["k"] = o.kind == StudyKind::Eigen ? o.k : 0;
  j["solver"] = o.linear_solver;
  j["params"] = o.method_params;
  if (o.kind == StudyKind::Cotan) {
    j["mesh_file"] = o.mesh_file;
    j["refine_vertices"] = o.refine_vertices;
    j["reference_values"] = o.reference_values;
    j["reference_laplacian"] = o.reference_laplacian;
  }
  return j;
}

std::string format_seconds(double s) {
  char buf[32];
  if (s < 60)
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 3600)
    std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
  else
    std::snprintf(buf, sizeof buf, "%dh%02dm", int(s) / 3600, (int(s) / 60) % 60);
  return buf;
}

// The plotting script: installed beside the program (../share/corrlap), else in the source tree.
std::string plot_script() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const auto installed = exe.parent_path().parent_path() / "share" / "corrlap" / "plot_study.py";
    if (std::filesystem::exists(installed)) return installed.string();
  }
#ifdef CORRLAP_PLOT_SCRIPT
  if (std::filesystem::exists(CORRLAP_PLOT_SCRIPT)) return CORRLAP_PLOT_SCRIPT;
#endif
  return "";
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// `corrlap study regularization` (paper §4.1, Fig. 15): its own options and table
// (studies/regularization_study.hpp).
void run_regularization(const StudyArgs& a) {
  if (a.method_params.any_given())
    throw InputError("study regularization: method parameters (--param, parameter flags) are not supported");
  RegularizationStudyOptions o;
  o.shapes = split_list(a.shapes);
  o.methods = split_list(a.methods);
  if (a.h_option->count() > 0) o.h = parse_grid_steps(a.h);
  if (a.resolutions_option->count() > 0 || o.h.empty()) {
    o.resolutions.clear();
    const std::string list = a.resolutions_option->count() > 0 ? a.resolutions : "32,64,128";
    for (const std::string& item : split_list(list)) {
      char* end = nullptr;
      const long n = std::strtol(item.c_str(), &end, 10);
      if (end != item.c_str() + item.size() || n < 8 || n > 2048)
        throw InputError("study regularization: --resolutions: '" + item + "' is not an integer in [8, 2048]");
      o.resolutions.push_back(int(n));
    }
    if (a.h_option->count() > 0) throw InputError("study regularization: give --h or --resolutions, not both");
  }
  o.normals = a.normals_given ? a.options.normals : "ii";
  o.alpha0.clear();
  for (const std::string& item : split_list(a.alpha0)) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size())
      throw InputError("study regularization: --alpha0: '" + item + "' is not a number (expected a list 0.1,1,10)",
                       "alpha0");
    o.alpha0.push_back(v);  // the study's options check the values
  }
  if (a.bbox_given) {
    o.min_aabb = a.bbox[0];
    o.max_aabb = a.bbox[1];
  }
  o.offset = a.options.offset;
  o.linear_solver = a.options.linear_solver == "auto" ? "cholmod" : a.options.linear_solver;
  o.validate();
  namespace fs = std::filesystem;
  const fs::path dir(a.out);
  const std::string table = (dir / "regularization.csv").string();
  if (fs::exists(table) && !a.overwrite)
    throw InputError("study: '" + a.out + "' already holds a regularization study (" + table +
                     "); pass --overwrite to start again");
  if (a.resume) throw InputError("study regularization: --resume is not supported (each unit takes seconds)");
  OutputFolder out(a.out, "out", study_output_mode(a));
  const std::string written = (fs::path(out.path()) / "regularization.csv").string();
  std::vector<RegularizationStudyRow> rows;
  const auto t0 = std::chrono::steady_clock::now();
  run_regularization_study(
      o,
      [&](const RegularizationStudyRow& r) {
        rows.push_back(r);
        write_regularization_csv(written, rows);  // rewritten after each unit: an interrupted run keeps its rows
      },
      [&](const RegularizationStudyProgress& p) {
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::cerr << "study regularization " << p.done << "/" << p.total << "  " << p.shape << " h=" << p.h << " "
                  << p.method;
        if (p.method != "alignment") std::cerr << " alpha0=" << p.alpha0;
        std::cerr << "  elapsed " << format_seconds(elapsed) << "\n";
      });
  if (!a.no_plots) run_plot_script(out.path());
  write_study_index(out.path(), "corrlap study regularization: " + a.out);
  out.commit();
  std::cout << "study: " << table << "\n";
  for (const RegularizationStudyRow& r : rows)
    std::cout << "  " << r.shape << " h=" << r.h << " " << r.method
              << (r.method == "alignment" ? std::string() : " alpha0=" + number_text(r.alpha0)) << ": distance "
              << r.distance_before << " -> " << r.distance_after << ", |dH| " << r.curvature_error_before << " -> "
              << r.curvature_error_after << ", area " << r.area_before << " -> " << r.area_after << "\n";
}

// An option of one kind of study given to another is refused rather than silently ignored.
void refuse_foreign_options(const StudyArgs& a) {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> kinds_of = {
      {"--h", {"forward", "backward", "eigen", "regularization"}},
      {"--functions", {"forward", "backward", "cotan"}},
      {"--shape", {"forward", "backward", "eigen"}},
      {"--bbox", {"forward", "backward", "eigen", "regularization"}},
      {"--offset", {"forward", "backward", "eigen", "regularization"}},
      {"--centers", {"forward", "backward", "eigen", "cotan"}},
      {"--seed", {"forward", "backward", "eigen", "cotan"}},
      {"--diffusion", {"forward", "cotan"}},
      {"--naive", {"forward", "cotan"}},
      {"-k", {"eigen"}},
      {"--resolutions", {"cotan", "regularization"}},
      {"--mesh-file", {"cotan"}},
      {"--refine-vertices", {"cotan"}},
      {"--reference-values", {"cotan"}},
      {"--reference-laplacian", {"cotan"}},
      {"--shapes", {"regularization"}},
      {"--alpha0", {"regularization"}},
      {"--allow-nonmanifold", {"regularization"}},
  };
  for (const auto& [flag, kinds] : kinds_of) {
    if (a.command->get_option(flag)->count() == 0 || std::find(kinds.begin(), kinds.end(), a.kind) != kinds.end())
      continue;
    std::string list;
    for (std::size_t i = 0; i < kinds.size(); ++i)
      list += (i == 0 ? "" : i + 1 == kinds.size() ? " and " : ", ") + kinds[i];
    throw InputError("study " + a.kind + ": " + flag + " does not apply to this study (it belongs to " + list +
                     (kinds.size() > 1 ? " studies)" : " study)"));
  }
}

void run(StudyArgs& a) {
  if (a.kind == "forward" || a.kind == "backward" || a.kind == "eigen" || a.kind == "cotan" ||
      a.kind == "regularization")
    refuse_foreign_options(a);
  if (a.kind == "regularization") return run_regularization(a);
  StudyOptions& o = a.options;
  o.kind = parse_study_kind(a.kind);
  o.method_params = a.method_params.key_values();
  o.methods = split_list(a.methods);
  if (o.kind == StudyKind::Cotan) {
    // The cotan study's truth is the mesh: its normals unless told otherwise; h = 2 / resolution.
    if (!a.normals_given) o.normals = "mesh";
    o.resolutions.clear();
    for (const std::string& item : split_list(a.resolutions)) {
      char* end = nullptr;
      const long n = std::strtol(item.c_str(), &end, 10);
      if (end != item.c_str() + item.size() || n < 4 || n > 4096)
        throw InputError("study cotan: --resolutions: '" + item + "' is not an integer in [4, 4096]");
      o.resolutions.push_back(int(n));
    }
  } else {
    o.h = parse_grid_steps(a.h);
  }
  o.functions = o.kind == StudyKind::Eigen ? std::vector<std::string>{} : split_list(a.functions);
  o.min_aabb = a.bbox[0];
  o.max_aabb = a.bbox[1];
  if (a.diffusion_option->count() > 0) o.diffusion = a.diffusion;
  o.validate();
  if (a.resume && a.overwrite) throw InputError("study: --resume and --overwrite exclude each other");

  namespace fs = std::filesystem;
  OutputFolder out(a.out, "out", study_output_mode(a));
  const fs::path dir(out.path());
  const bool eigen = o.kind == StudyKind::Eigen;
  const std::string results = (dir / (eigen ? "eigen.csv" : "results.csv")).string();
  const std::string options_file = (dir / "study.json").string();
  const nlohmann::json fixed = fixed_options(o);
  // Units already computed (resume): (h, centre, method) with every requested function present.
  std::set<std::tuple<double, int, std::string>> done;
  // The rows in the file per unit: a unit recomputed for a new function must not repeat them.
  std::map<std::tuple<double, int, std::string>, std::set<std::string>> seen;
  if (!a.overwrite && fs::exists(results)) {
    if (!a.resume) {
      throw InputError("study: '" + a.out + "' already holds a study (" + results +
                       "); pass --resume to continue it or --overwrite to start again");
    } else {
      if (fs::exists(options_file)) {
        std::ifstream in(options_file);
        const nlohmann::json before = nlohmann::json::parse(in, nullptr, false);
        for (const auto& [key, value] : fixed.items())
          if (before.is_discarded() || !before.contains(key) || before[key] != value)
            throw InputError(
                "study: --resume: option '" + key + "' differs from the study in '" + a.out + "' (" +
                (before.is_discarded() || !before.contains(key) ? std::string("missing") : before[key].dump()) +
                " there, " + value.dump() + " now); use another --out or --overwrite");
      }
      if (eigen) {
        for (const EigenRow& r : read_eigen_csv(results)) seen[{r.h, r.center, r.method}].insert("eigen");
      } else {
        for (const StudyRow& r : read_results_csv(results)) seen[{r.h, r.center, r.method}].insert(r.function);
      }
      for (const auto& [unit, functions] : seen) {
        bool all = true;
        for (const std::string& f : eigen ? std::vector<std::string>{"eigen"} : o.functions)
          all = all && functions.count(f);
        if (all) done.insert(unit);
      }
      std::cerr << "study: resuming " << a.out << ": " << done.size() << " unit(s) already computed\n";
    }
  }
  {
    std::ofstream out(options_file);
    out << fixed.dump(2) << "\n";
  }

  const bool tty = isatty(STDERR_FILENO) != 0;
  const auto t0 = std::chrono::steady_clock::now();
  double last_printed = -1, last_h = 0;
  StudyCallbacks cb;
  cb.already_done = [&](double h, int center, const std::string& method) {
    for (const auto& [uh, uc, um] : done)
      if (uc == center && um == method && std::abs(uh - h) <= 1e-12 * h) return true;
    return false;
  };
  cb.rows = [&](const std::vector<StudyRow>& rows) {
    std::vector<StudyRow> fresh;
    for (const StudyRow& r : rows) {
      bool present = false;
      for (const auto& [unit, functions] : seen) {
        const auto& [uh, uc, um] = unit;
        present = present || (uc == r.center && um == r.method && std::abs(uh - r.h) <= 1e-12 * r.h &&
                              functions.count(r.function) > 0);
      }
      if (!present) fresh.push_back(r);
    }
    write_results_csv(results, fresh, true);
  };
  cb.eigen_rows = [&](const std::vector<EigenRow>& rows) { write_eigen_csv(results, rows, true); };
  cb.progress = [&](const StudyProgress& p) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double eta = p.cost_fraction > 0 ? elapsed * (1.0 - p.cost_fraction) / p.cost_fraction : 0.0;
    // A TTY gets a bar redrawn in place; a log one line per 10% of the work, at each new grid
    // step (the natural milestones of a study) and at the end.
    const bool new_h = p.h != last_h;
    last_h = p.h;
    if (!tty && p.done != p.total && !new_h && p.cost_fraction < last_printed + 0.1) return;
    last_printed = p.cost_fraction;
    const int width = 24, filled = int(std::lround(p.cost_fraction * width));
    std::ostringstream line;
    line << "study " << to_string(o.kind) << " [" << std::string(std::size_t(filled), '#')
         << std::string(std::size_t(width - filled), '.') << "] " << p.done << "/" << p.total << "  h=" << p.h
         << " centre " << p.center + 1 << "/" << o.centers << " " << p.method << "  elapsed " << format_seconds(elapsed)
         << "  ETA " << format_seconds(eta);
    if (tty)
      std::cerr << "\r" << line.str() << "\033[K" << (p.done == p.total ? "\n" : "") << std::flush;
    else
      std::cerr << line.str() << "\n";
  };
  run_study(o, cb);
  finish_study(out.path(), a.out, eigen, !a.no_plots);
  out.commit();
}

}  // namespace

void finish_study(const std::string& out, const std::string& shown, bool eigen, bool plots) {
  namespace fs = std::filesystem;
  const fs::path dir(out), shown_dir(shown);
  const std::string results = eigen ? "eigen.csv" : "results.csv";
  // Tables from every row in the file (this run's and the resumed ones).
  std::cout << "study: " << (shown_dir / results).string() << "\n";
  if (!eigen) {
    const std::vector<StudyRow> rows = read_results_csv((dir / results).string());
    write_summary_csv((dir / "summary.csv").string(), summarize(rows));
    const std::vector<OrderRow> fitted = fit_orders(rows);
    write_orders_csv((dir / "orders.csv").string(), fitted);
    std::cout << "study: " << (shown_dir / "summary.csv").string() << "\nstudy: " << (shown_dir / "orders.csv").string()
              << "\n";
    for (const std::string& shortfall : order_shortfalls(fitted))
      std::cerr << "warning: study: " << (shown_dir / "orders.csv").string() << ": " << shortfall << "\n";
    for (const OrderRow& r : fitted)
      if (r.norm == std::string("l2") && !std::isnan(r.order))
        std::cout << "  order " << r.study << " " << r.method << " " << r.normals << " " << r.function
                  << " L2: " << r.order
                  << (std::isnan(r.low) ? std::string()
                                        : " [" + std::to_string(r.low) + ", " + std::to_string(r.high) + "]")
                  << "\n";
  }
  if (plots) run_plot_script(out);
  write_study_index(out, "corrlap study: " + shown);
  std::cout << "study: " << (shown_dir / "index.html").string() << " (the plots and tables; open it in a browser)\n";
}

void run_plot_script(const std::string& out) {
  namespace fs = std::filesystem;
  const std::string script = plot_script();
  const char* python_env = std::getenv("CORRLAP_PYTHON");
  const std::string python = python_env && *python_env        ? python_env
                             : fs::exists("/usr/bin/python3") ? "/usr/bin/python3"
                                                              : "python3";
  if (script.empty()) {
    std::cerr << "study: plots skipped (plot_study.py not found beside the program)\n";
    return;
  }
  const std::string command = shell_quote(python) + " " + shell_quote(script) + " " + shell_quote(out);
  std::fflush(stdout);
  std::cout.flush();
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 3)
    std::cerr << "study: plots skipped: matplotlib is not available (apt-get install python3-matplotlib)\n";
  else if (code != 0)
    std::cerr << "warning: study: the plotting script failed (" << command << ", exit " << code
              << "); the tables are written\n";
}

namespace {

RegisterCommand reg(45, "study", [](CLI::App& app) {
  auto args = std::make_shared<StudyArgs>();
  auto* cmd =
      app.add_subcommand("study",
                         "the paper's evaluations: forward | backward | eigen errors of several methods over grid "
                         "steps and centres -> CSV tables and plots (docs/studies.md)");
  cmd->add_option("study", args->kind, "forward | backward | eigen | cotan | regularization")->required();
  cmd->add_option("--methods", args->methods, "comma-separated discretizations")->capture_default_str();
  args->h_option =
      cmd->add_option("--h", args->h, "grid steps: a comma list (0.1,0.05) or A:B:N (N log-spaced steps from A to B)")
          ->capture_default_str();
  cmd->add_option("--functions", args->functions, "forward/backward: test functions x2, expx, p6")
      ->capture_default_str();
  cmd->add_option("--normals", args->options.normals,
                  "normal source: true | ii (II with k = 3, alpha = 1/3) | exact (the shape's normal at each vertex); "
                  "cotan: mesh (default: the mesh's normals, projected, as given normals) | ii; regularization: ii "
                  "(default) | true")
      ->check(CLI::IsMember({"true", "ii", "exact", "mesh"}))
      ->each([args](const std::string&) { args->normals_given = true; })
      ->capture_default_str();
  cmd->add_option("--mesh-file", args->options.mesh_file, "cotan: the triangle mesh (OBJ, PLY, OFF)");
  args->resolutions_option =
      cmd->add_option("--resolutions", args->resolutions,
                      "cotan: voxels along the mesh's longest side (h = 2 / N); regularization: along each shape's "
                      "longest side (default 32,64,128)")
          ->capture_default_str();
  cmd->add_option("--shapes", args->shapes, "regularization: implicit shapes")->capture_default_str();
  cmd->add_flag("--allow-nonmanifold", args->allow_nonmanifold, kAllowNonmanifoldNote);
  cmd->add_option(
         "--alpha0", args->alpha0,
         "regularization: attachment weights alpha = alpha0 / (h size)^2, a list swept (0.01,0.1,1,10,100,1000 "
         "for the paper's Fig. 13)")
      ->capture_default_str();
  cmd->add_option("--refine-vertices", args->options.refine_vertices,
                  "cotan: Loop-subdivide the mesh to at least this many vertices (0: as given)")
      ->capture_default_str();
  cmd->add_option("--centers", args->options.centers,
                  "centres per h: uniform in [-h/2, h/2]^3 (centre 0 when 1; docs/math.md §10.1)")
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_option("--seed", args->options.seed, "seed of the centre draws")->capture_default_str();
  args->diffusion_option =
      cmd->add_option("--diffusion", args->diffusion, "forward, cotan: dt = diffusion * h (docs/math.md §10.3)")
          ->capture_default_str();
  cmd->add_flag("--naive", args->options.naive,
                "forward, cotan: no diffusion, X = M^-1 L f (dt = 0; excludes --diffusion)");
  cmd->add_option("-k", args->options.k, "eigen: number of eigenvalues")->capture_default_str();
  cmd->add_option("--shape", args->options.shape,
                  "implicit shape: sphere1 (the exact values are those of the unit sphere; cotan: the mesh)")
      ->capture_default_str();
  cmd->add_option("--bbox", args->bbox, "digitization box MIN MAX (regularization: default -10 10)")
      ->expected(2)
      ->capture_default_str()
      ->each([args](const std::string&) { args->bbox_given = true; });
  cmd->add_option("--offset", args->options.offset, "extra voxels around the box")->capture_default_str();
  cmd->add_option(
         "--solver", args->options.linear_solver,
         "linear solver backend, or auto (forward and cotan: Jacobi cg; backward and eigen: cholmod, cg for operators "
         "with > 64 nonzeros per row: the heat kernel)")
      ->capture_default_str();
  args->method_params.add_options(*cmd, /*method_flag=*/false);
  cmd->add_option("--reference-values", args->options.reference_values,
                  "cotan: interpolated (the paper: the mesh's vertex values, interpolated) | at-foot (the "
                  "function evaluated at the projected point; the Laplacian stays interpolated)")
      ->check(CLI::IsMember({"interpolated", "at-foot"}))
      ->capture_default_str();
  cmd->add_option("--reference-laplacian", args->options.reference_laplacian,
                  "cotan: plain (the truth is M^-1 L f of the mesh) | diffused ((M - dt L)^-1 L f on the mesh, "
                  "the same smoothing as the digital side)")
      ->check(CLI::IsMember({"plain", "diffused"}))
      ->capture_default_str();
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->add_flag("--resume", args->resume, "continue the study in --out: computed units are not recomputed");
  cmd->add_flag("--overwrite", args->overwrite, "replace the study in --out");
  cmd->add_flag("--no-plots", args->no_plots, "tables only");
  args->command = cmd;
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

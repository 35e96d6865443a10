#pragma once
// Shared helpers for the unit tests.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace corrlap::test {

/// Directory of the reference data (../shared/reference); tests that need it fail if absent.
inline std::string reference_dir() { return CORRLAP_REFERENCE_DIR; }

/// A fresh scratch file path under the build tree.
inline std::string tmp_path(const std::string& name) {
  std::filesystem::create_directories(CORRLAP_TEST_TMP);
  return std::string(CORRLAP_TEST_TMP) + "/" + name;
}

inline void write_text(const std::string& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary);
  out << content;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

#ifdef CORRLAP_CLI
/// Runs the CLI with arguments; returns the exit code, stdout in `out`, stderr in `err`.
inline int run_cli(const std::string& args, std::string* out = nullptr, std::string* err = nullptr) {
  static int counter = 0;
  // ctest runs test cases as parallel processes: the pid keeps scratch names apart.
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(++counter);
  const std::string o = tmp_path("cli_out_" + tag + ".txt");
  const std::string e = tmp_path("cli_err_" + tag + ".txt");
  const std::string cmd = std::string(CORRLAP_CLI) + " " + args + " >" + o + " 2>" + e + " </dev/null";
  const int status = std::system(cmd.c_str());
  if (out) *out = read_text(o);
  if (err) *err = read_text(e);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}
#endif

}  // namespace corrlap::test

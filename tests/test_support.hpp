#pragma once
// Shared helpers for the unit tests.
#include <unistd.h>

#include <array>
#include <cmath>
#include <corrlap/core/polygon_mesh.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace corrlap::test {

/// Directory of the reference data (tests/data, see its README.md).
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

// Icosahedron subdivided `levels` times, projected on the sphere (centre c, radius r).
inline PolygonMesh icosphere(int levels, double r = 1.0, const Eigen::Vector3d& c = Eigen::Vector3d::Zero()) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[std::size_t(a)] + v[std::size_t(b)]).normalized());
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), cc = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, cc});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], cc, b});
      g.push_back({a, b, cc});
    }
    f = g;
  }
  PolygonMesh m;
  m.positions.resize(Eigen::Index(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.positions.row(Eigen::Index(i)) = (c + r * v[i]).transpose();
  for (const auto& tri : f) m.faces.push_back({tri[0], tri[1], tri[2]});
  return m;
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

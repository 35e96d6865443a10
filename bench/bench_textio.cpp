// Text (and binary PLY) I/O throughput: MB/s = file bytes / seconds, written and read back, for
// the files of a digitized sphere1 (box -1.5..1.5). Goal: >= 200 MB/s for OBJ, PLY,
// normals and Matrix Market, exact round trips, memory of a read <= 1.5x the data it holds.
//
//   ./build/bench/bench_textio                 # h = 0.005 (~750 k faces)
//   ./build/bench/bench_textio --h 0.002       # ~4.7 M faces, the size of the goal
//   ./build/bench/bench_textio --dir /tmp      # where the files go (default: the current folder)
//
// Each file is written and read once (the files are hundreds of MB: one run is long enough to time;
// the first read may include the page cache warming up, so the file is read twice and the faster
// read is shown). "read peak" is the growth of the peak resident memory during the read (measured
// in a fresh process running `bench_textio --peak obj|ply|off|normals|scalars|mtx FILE`), "held" the
// bytes of the arrays the read returns; "exact" says whether every array read back is bitwise equal
// to what was written. The ASCII PLY and the OFF file are written by this file (the library writes
// binary PLY and does not write OFF).
#include <benchmark/benchmark.h>

#include <Eigen/Sparse>
#include <charconv>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/methods.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "support.hpp"

using namespace corrlap;

namespace {

double seconds(const std::function<void()>& f) {
  const Stopwatch watch;
  f();
  return watch.elapsed();
}

template <class A>
bool same_bits(const A& a, const A& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(typename A::Scalar) * std::size_t(a.size())) == 0;
}

bool same_mesh(const PolygonMesh& a, const PolygonMesh& b) {
  if (!same_bits(a.positions, b.positions) || a.faces.size() != b.faces.size()) return false;
  for (std::size_t f = 0; f < a.faces.size(); ++f) {
    if (a.faces[f].size() != b.faces[f].size()) return false;
    for (std::size_t j = 0; j < a.faces[f].size(); ++j)
      if (a.faces[f][j] != b.faces[f][j]) return false;
  }
  return true;
}

bool same_matrix(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  const auto n = std::size_t(a.nonZeros());
  return a.rows() == b.rows() && a.cols() == b.cols() && a.nonZeros() == b.nonZeros() &&
         std::memcmp(a.outerIndexPtr(), b.outerIndexPtr(), sizeof(int) * std::size_t(a.outerSize() + 1)) == 0 &&
         std::memcmp(a.innerIndexPtr(), b.innerIndexPtr(), sizeof(int) * n) == 0 &&
         std::memcmp(a.valuePtr(), b.valuePtr(), sizeof(double) * n) == 0;
}

double mesh_bytes(const PolygonMesh& m) {
  double corners = 0;
  for (std::size_t f = 0; f < m.faces.size(); ++f) corners += double(m.faces[f].size());
  // positions, one int per corner and one 64-bit offset per face (flat face storage)
  return 24.0 * double(m.positions.rows()) + 4.0 * corners + 8.0 * double(m.faces.size() + 1);
}

// ASCII PLY (or OFF) with x y z as double (17 digits) and "n i1 .. in" face lines.
void write_ascii_mesh(const std::string& path, const PolygonMesh& m, bool off) {
  std::string out = off ? "OFF\n" + std::to_string(m.positions.rows()) + " " + std::to_string(m.faces.size()) + " 0\n"
                        : "ply\nformat ascii 1.0\nelement vertex " + std::to_string(m.positions.rows()) +
                              "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
                              std::to_string(m.faces.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  char buf[32];
  auto put = [&](auto v, char sep) {
    char* e;
    if constexpr (std::is_floating_point_v<decltype(v)>)
      e = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 17).ptr;
    else
      e = std::to_chars(buf, buf + sizeof buf, v).ptr;
    *e++ = sep;
    out.append(buf, e);
  };
  for (Eigen::Index v = 0; v < m.positions.rows(); ++v)
    for (int c = 0; c < 3; ++c) put(m.positions(v, c), c == 2 ? '\n' : ' ');
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    put(int(m.faces[f].size()), ' ');
    for (std::size_t j = 0; j < m.faces[f].size(); ++j) put(m.faces[f][j], j + 1 == m.faces[f].size() ? '\n' : ' ');
  }
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(out.data(), 1, out.size(), f) != out.size() || std::fclose(f) != 0) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    std::exit(1);
  }
}

void row(const char* what, const std::string& path, double write_s, double read_s, double peak_mib, double held,
         bool exact) {
  const double mb = double(std::filesystem::file_size(path)) / 1e6;
  std::printf("%-12s %9.1f %9s %9s %9.1f %9.1f %11.1f %9.1f %6.2fx  %s\n", what, mb,
              write_s > 0 ? std::to_string(write_s).substr(0, 5).c_str() : "-",
              write_s > 0 ? std::to_string(int(mb / write_s)).c_str() : "-", read_s, mb / read_s, peak_mib,
              held / (1 << 20), peak_mib * (1 << 20) / held, exact ? "yes" : "NO");
  std::fflush(stdout);
}

std::string self_exe;

// Peak memory of one read in a fresh process (`--peak KIND PATH`): in this one, the heap freed by
// earlier steps would be reused and hide the growth.
double read_peak_mib(const char* kind, const std::string& path) {
  const std::string cmd = self_exe + " --peak " + kind + " '" + path + "'";
  std::FILE* p = popen(cmd.c_str(), "r");
  double mib = -1;
  if (!p || std::fscanf(p, "%lf", &mib) != 1) mib = -1;
  if (p) pclose(p);
  return mib;
}

int peak_mode(const std::string& kind, const std::string& path) {
  const double before = bench::rss_mib();
  if (kind == "obj") benchmark::DoNotOptimize(read_obj(path).positions.data());
  if (kind == "ply") benchmark::DoNotOptimize(read_ply(path).positions.data());
  if (kind == "off") benchmark::DoNotOptimize(read_off(path).positions.data());
  if (kind == "normals") benchmark::DoNotOptimize(read_normals(path).data());
  if (kind == "scalars") benchmark::DoNotOptimize(read_scalars(path).data());
  if (kind == "mtx") benchmark::DoNotOptimize(read_matrix_market(path).valuePtr());
  std::printf("%.1f\n", bench::peak_rss_mib() - before);
  return 0;
}

// Reads twice (page cache warm on the second) and keeps the faster time; the peak comes from a
// separate process.
template <class R>
void measure_read(const std::function<R()>& read, R& result, double& read_s, double& peak_mib, const char* kind,
                  const std::string& path) {
  read_s = 1e300;
  for (int rep = 0; rep < 2; ++rep) {
    result = R{};
    read_s = std::min(read_s, seconds([&] { result = read(); }));
  }
  peak_mib = read_peak_mib(kind, path);
}

}  // namespace

int main(int argc, char** argv) {
  double h = 0.005;
  std::string dir = ".";
  self_exe = std::filesystem::read_symlink("/proc/self/exe").string();
  if (argc == 4 && !std::strcmp(argv[1], "--peak")) return peak_mode(argv[2], argv[3]);
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--h") && i + 1 < argc)
      h = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--dir") && i + 1 < argc)
      dir = argv[++i];
    else {
      std::fprintf(stderr, "usage: %s [--h H] [--dir DIR]\n", argv[0]);
      return 2;
    }
  }
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  const ImplicitShape shape = make_implicit_shape("sphere1");
  const SurfelMesh surf = extract_surface(digitize(shape, p));
  const PolygonMesh mesh = to_polygon_mesh(surf);
  const Eigen::MatrixX3d normals = true_face_normals(shape, surf);
  // Scalars with every kind of value: tiny, huge, negative, integral, subnormal.
  Eigen::VectorXd scalars = normals.col(0);
  for (Eigen::Index i = 0; i < scalars.size(); i += 7) scalars[i] *= (i % 2 ? 1e300 : -1e-310);
  for (Eigen::Index i = 3; i < scalars.size(); i += 11) scalars[i] = double(i);
  const Eigen::SparseMatrix<double> L = corrected_fem(surf, normals).L;
  std::printf("sphere1 h=%g: %lld vertices, %zu faces, L %lld nonzeros\n", h, (long long)mesh.positions.rows(),
              mesh.faces.size(), (long long)L.nonZeros());
  std::printf("%-12s %9s %9s %9s %9s %9s %11s %9s %7s  %s\n", "file", "MB", "write s", "MB/s", "read s", "MB/s",
              "read peak", "held MiB", "ratio", "exact");

  double w = 0, r = 0, peak = 0;
  {
    const std::string path = dir + "/bench_textio.obj";
    w = seconds([&] { write_obj(path, mesh); });
    PolygonMesh back;
    measure_read<PolygonMesh>([&] { return read_obj(path); }, back, r, peak, "obj", path);
    row("OBJ", path, w, r, peak, mesh_bytes(back), same_mesh(mesh, back));
    std::filesystem::remove(path);
  }
  {
    const std::string path = dir + "/bench_textio.ply";
    w = seconds([&] { write_ply(path, mesh); });
    PolygonMesh back;
    measure_read<PolygonMesh>([&] { return read_ply(path); }, back, r, peak, "ply", path);
    row("PLY binary", path, w, r, peak, mesh_bytes(back), same_mesh(mesh, back));
    std::filesystem::remove(path);
  }
  {
    const std::string path = dir + "/bench_textio_ascii.ply";
    write_ascii_mesh(path, mesh, false);
    PolygonMesh back;
    measure_read<PolygonMesh>([&] { return read_ply(path); }, back, r, peak, "ply", path);
    row("PLY ascii", path, 0, r, peak, mesh_bytes(back), same_mesh(mesh, back));
    std::filesystem::remove(path);
  }
  {
    const std::string path = dir + "/bench_textio.off";
    write_ascii_mesh(path, mesh, true);
    PolygonMesh back;
    measure_read<PolygonMesh>([&] { return read_off(path); }, back, r, peak, "off", path);
    row("OFF", path, 0, r, peak, mesh_bytes(back), same_mesh(mesh, back));
    std::filesystem::remove(path);
  }
  {
    const std::string path = dir + "/bench_textio_normals.txt";
    w = seconds([&] { write_normals(path, normals); });
    Eigen::MatrixX3d back;
    measure_read<Eigen::MatrixX3d>([&] { return read_normals(path); }, back, r, peak, "normals", path);
    row("normals", path, w, r, peak, 8.0 * double(back.size()), same_bits(normals, back));
    std::filesystem::remove(path);
  }
  {
    const std::string path = dir + "/bench_textio_scalars.txt";
    w = seconds([&] { write_scalars(path, scalars); });
    Eigen::VectorXd back;
    measure_read<Eigen::VectorXd>([&] { return read_scalars(path); }, back, r, peak, "scalars", path);
    row("scalars", path, w, r, peak, 8.0 * double(back.size()), same_bits(scalars, back));
    std::filesystem::remove(path);
  }
  {
    const std::string path = dir + "/bench_textio_L.mtx";
    w = seconds([&] { write_matrix_market(path, L); });
    Eigen::SparseMatrix<double> back;
    measure_read<Eigen::SparseMatrix<double>>([&] { return read_matrix_market(path); }, back, r, peak, "mtx", path);
    row("MatrixMarket", path, w, r, peak, bench::sparse_bytes(back), same_matrix(L, back));
    std::filesystem::remove(path);
  }
  return 0;
}

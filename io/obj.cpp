// Wavefront OBJ reader and writer.
#include <cerrno>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "mesh_io.hpp"

namespace corrlap {

namespace {
[[noreturn]] void fail(const std::string& path, std::size_t line, const std::string& what) {
  std::ostringstream os;
  os << "OBJ file '" << path << "'";
  if (line) os << ", line " << line;
  os << ": " << what;
  throw IoError(os.str());
}

// Upper bound on elements, to reject absurd files before allocating.
constexpr std::size_t kMaxElements = std::size_t{1} << 31;
}  // namespace

PolygonMesh read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, 0, "cannot open");
  PolygonMesh mesh;
  std::vector<double> xyz;
  std::string line;
  std::size_t lineno = 0;
  std::vector<std::vector<long>> raw_faces;
  std::vector<std::size_t> face_lines;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      double p[3];
      for (double& c : p) {
        std::string tok;
        if (!(ls >> tok)) fail(path, lineno, "vertex with fewer than 3 coordinates");
        const char* b = tok.data();
        auto [ptr, ec] = std::from_chars(b, b + tok.size(), c);
        if (ec != std::errc() || ptr != b + tok.size() || !std::isfinite(c))
          fail(path, lineno, "malformed or non-finite coordinate '" + tok.substr(0, 40) + "'");
      }
      xyz.insert(xyz.end(), p, p + 3);
      if (xyz.size() / 3 > kMaxElements) fail(path, lineno, "too many vertices");
    } else if (tag == "f") {
      std::vector<long> ids;
      std::string tok;
      while (ls >> tok) {
        const std::string first = tok.substr(0, tok.find('/'));
        long id = 0;
        auto [ptr, ec] = std::from_chars(first.data(), first.data() + first.size(), id);
        if (ec != std::errc() || ptr != first.data() + first.size() || id == 0)
          fail(path, lineno, "malformed face index '" + tok.substr(0, 40) + "'");
        ids.push_back(id);
      }
      if (ids.size() < 3) fail(path, lineno, "face with fewer than 3 corners");
      raw_faces.push_back(std::move(ids));
      face_lines.push_back(lineno);
      if (raw_faces.size() > kMaxElements) fail(path, lineno, "too many faces");
    }
    // vn, vt, o, g, s, usemtl, mtllib: ignored
  }
  if (in.bad()) fail(path, lineno, "read error");
  const long nv = long(xyz.size() / 3);
  if (nv == 0) fail(path, 0, "no vertex (empty or not an OBJ file)");
  if (raw_faces.empty()) fail(path, 0, "no face");
  mesh.positions = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(xyz.data(), nv, 3);
  mesh.faces.resize(raw_faces.size());
  for (std::size_t f = 0; f < raw_faces.size(); ++f) {
    for (long id : raw_faces[f]) {
      const long v = id > 0 ? id - 1 : nv + id;  // negative: relative to the end
      if (v < 0 || v >= nv) {
        std::ostringstream os;
        os << "face index " << id << " out of range (" << nv << " vertices)";
        fail(path, face_lines[f], os.str());
      }
      mesh.faces[f].push_back(int(v));
    }
  }
  return mesh;
}

void write_obj(const std::string& path, const PolygonMesh& mesh) {
  for (Eigen::Index v = 0; v < mesh.positions.rows(); ++v)
    for (int c = 0; c < 3; ++c)
      io_detail::require_finite(mesh.positions(v, c), path, "OBJ", "vertex", (long long)v + 1);
  io_detail::OutputFile f(path, "OBJ");
  std::fprintf(f.get(), "# corrlap mesh: %lld vertices, %zu faces\n", (long long)mesh.positions.rows(),
               mesh.faces.size());
  for (Eigen::Index v = 0; v < mesh.positions.rows(); ++v)
    std::fprintf(f.get(), "v %.17g %.17g %.17g\n", mesh.positions(v, 0), mesh.positions(v, 1), mesh.positions(v, 2));
  for (const auto& face : mesh.faces) {
    std::fputc('f', f.get());
    for (int id : face) std::fprintf(f.get(), " %d", id + 1);
    std::fputc('\n', f.get());
  }
  f.commit();
}

}  // namespace corrlap

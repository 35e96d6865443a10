// Wavefront OBJ reader and writer.
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/line_reader.hpp>
#include <corrlap/io/detail/mesh_records.hpp>
#include <corrlap/io/detail/text_writer.hpp>
#include <corrlap/io/detail/tokens.hpp>
#include <optional>
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

// The tag of an OBJ line ("v", "f", "vn", "#"...): its first token.
std::string_view tag_of(io_detail::Tokens& tokens) {
  std::string_view tag;
  return tokens.next(tag) ? tag : std::string_view{};
}
}  // namespace

// Two passes over the file: the first counts vertices, faces and corners, so that the mesh is
// allocated once at its final size (no growing vectors: a read holds little more than its result);
// the second parses. Negative indices are relative to the end of the vertex list, as before.
PolygonMesh read_obj(const std::string& path) {
  io_detail::LineReader in(path);
  if (!in.is_open()) fail(path, 0, "cannot open");
  std::size_t nv = 0, nf = 0, corners = 0;
  std::string_view line, tok;
  while (in.next(line)) {
    io_detail::Tokens ls(line);
    const std::string_view tag = tag_of(ls);
    if (tag == "v") {
      if (++nv > kMaxElements) fail(path, in.line_number(), "too many vertices");
    } else if (tag == "f") {
      if (++nf > kMaxElements) fail(path, in.line_number(), "too many faces");
      while (ls.next(tok)) ++corners;
    }
  }
  if (in.error()) fail(path, in.line_number(), "read error");
  io_detail::check_budget("OBJ file '" + path + "'", 24.0 * double(nv) + 4.0 * double(corners) + 8.0 * double(nf),
                          io_detail::readable_count(nv) + " vertices and " + io_detail::readable_count(nf) + " faces");
  PolygonMesh mesh;
  mesh.positions.resize(Eigen::Index(nv), 3);
  mesh.faces.reserve(nf, corners);

  in.rewind();
  std::size_t v = 0;
  // Index errors are reported after the whole file has parsed (a malformed line anywhere wins).
  std::optional<std::pair<std::size_t, long>> bad_index;  // line, index
  const long lnv = long(nv);
  while (in.next(line)) {
    io_detail::Tokens ls(line);
    const std::string_view tag = tag_of(ls);
    if (tag == "v") {
      if (v == nv) fail(path, in.line_number(), "file changed while reading");
      for (int c = 0; c < 3; ++c) {
        double x = 0;
        if (!ls.next(tok)) fail(path, in.line_number(), "vertex with fewer than 3 coordinates");
        if (!io_detail::parse_number(tok, x) || !std::isfinite(x))
          fail(path, in.line_number(), "malformed or non-finite coordinate '" + std::string(tok.substr(0, 40)) + "'");
        mesh.positions(Eigen::Index(v), c) = x;
      }
      ++v;
    } else if (tag == "f") {
      if (mesh.faces.size() == nf) fail(path, in.line_number(), "file changed while reading");
      mesh.faces.start_face();
      std::size_t n = 0;
      while (ls.next(tok)) {
        long id = 0;  // "f v/vt/vn": the vertex is the part before the first '/'
        if (!io_detail::parse_number(tok.substr(0, tok.find('/')), id) || id == 0)
          fail(path, in.line_number(), "malformed face index '" + std::string(tok.substr(0, 40)) + "'");
        const long w = id > 0 ? id - 1 : lnv + id;  // negative: relative to the end
        if ((w < 0 || w >= lnv) && !bad_index) bad_index.emplace(in.line_number(), id);
        mesh.faces.add_corner(w < 0 || w >= lnv ? 0 : int(w));
        ++n;
      }
      if (n < 3) fail(path, in.line_number(), "face with fewer than 3 corners");
    }
    // vn, vt, o, g, s, usemtl, mtllib: ignored
  }
  if (in.error()) fail(path, in.line_number(), "read error");
  if (v != nv || mesh.faces.size() != nf) fail(path, 0, "file changed while reading");
  if (nv == 0) fail(path, 0, "no vertex (empty or not an OBJ file)");
  if (nf == 0) fail(path, 0, "no face");
  if (bad_index) {
    std::ostringstream os;
    os << "face index " << bad_index->second << " out of range (" << nv << " vertices)";
    fail(path, bad_index->first, os.str());
  }
  return mesh;
}

void write_obj(const std::string& path, const PolygonMesh& mesh, const std::vector<std::string>& comments) {
  for (const std::string& c : comments)
    if (c.find_first_of("\r\n") != std::string::npos)
      throw IoError("OBJ file '" + path + "': a header comment holds a line break");
  for (Eigen::Index v = 0; v < mesh.positions.rows(); ++v)
    for (int c = 0; c < 3; ++c)
      io_detail::require_finite(mesh.positions(v, c), path, "OBJ", "vertex", (long long)v + 1);
  io_detail::TextWriter out(path, "OBJ");
  out.write(io_detail::obj_header(mesh.positions.rows(), std::int64_t(mesh.faces.size()), comments));
  for (Eigen::Index v = 0; v < mesh.positions.rows(); ++v)
    io_detail::put_obj_vertex(out, mesh.positions(v, 0), mesh.positions(v, 1), mesh.positions(v, 2));
  for (const auto face : mesh.faces) io_detail::put_obj_face(out, face);
  out.commit();
}

namespace io_detail {

std::string obj_header(std::int64_t vertices, std::int64_t faces, const std::vector<std::string>& comments) {
  std::string out;
  StringSink sink(out);
  sink.write("# corrlap mesh: ");
  sink.write_int(vertices);
  sink.write(" vertices, ");
  sink.write_int(faces);
  sink.write(" faces\n");
  for (const std::string& c : comments) {
    sink.write("# ");
    sink.write(c);
    sink.write('\n');
  }
  return out;
}

}  // namespace io_detail

}  // namespace corrlap

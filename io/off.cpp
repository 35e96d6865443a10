// Object File Format (OFF) reader: "OFF" header, counts "nv nf ne", vertices, faces "n i1 .. in".
#include <algorithm>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/block_readers.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/corner_reserve.hpp>
#include <corrlap/io/detail/line_reader.hpp>
#include <corrlap/io/detail/tokens.hpp>
#include <cstdint>
#include <sstream>
#include <vector>

#include "mesh_io.hpp"

namespace corrlap {

namespace {

[[noreturn]] void fail(const std::string& path, std::size_t line, const std::string& what) {
  std::ostringstream os;
  os << "OFF file '" << path << "'";
  if (line) os << ", line " << line;
  os << ": " << what;
  throw IoError(os.str());
}

// Tokens of the file's lines with their line numbers; '#' starts a comment. The tokens are views
// into the reader's buffer, valid until the next line is read.
class LineTokens {
 public:
  LineTokens(io_detail::LineReader& in, const std::string& path) : in_(in), path_(path) {}
  // Next non-empty line split into tokens; false at end of file.
  bool next_line(std::vector<std::string_view>& toks) {
    std::string_view line, t;
    while (in_.next(line)) {
      io_detail::Tokens ls(line.substr(0, line.find('#')));
      toks.clear();
      while (ls.next(t)) toks.push_back(t);
      if (!toks.empty()) return true;
    }
    if (in_.error()) fail(path_, in_.line_number(), "read error");
    return false;
  }
  std::size_t line() const { return in_.line_number(); }

 private:
  io_detail::LineReader& in_;
  const std::string& path_;
};

std::string str(std::string_view s, std::size_t n = 40) { return std::string(s.substr(0, n)); }

constexpr long long kMaxCount = 1LL << 31;

}  // namespace

PolygonMesh io_detail::read_off(const std::string& path, std::size_t block_bytes) {
  io_detail::LineReader in(path, block_bytes);
  if (!in.is_open()) fail(path, 0, "cannot open");
  LineTokens tk(in, path);
  std::vector<std::string_view> t;
  if (!tk.next_line(t)) fail(path, 0, "empty file");
  // Header: OFF, COFF, NOFF, CNOFF...: extra per-vertex columns (colours, normals) are ignored.
  const std::string kw(t[0]);
  if (kw.size() < 3 || kw.compare(kw.size() - 3, 3, "OFF") != 0)
    fail(path, tk.line(), "not an OFF file (header '" + kw.substr(0, 40) + "', expected OFF)");
  if (kw.find("4") != std::string::npos || kw.find("n") != std::string::npos)
    fail(path, tk.line(), "unsupported OFF variant '" + kw + "' (only 3D OFF/COFF/NOFF)");
  std::vector<std::string_view> counts(t.begin() + 1, t.end());
  if (counts.empty() && !tk.next_line(counts)) fail(path, tk.line(), "truncated: missing the counts line");
  long long nv = 0, nf = 0;
  if (counts.size() < 2 || !io_detail::parse_number(counts[0], nv) || !io_detail::parse_number(counts[1], nf) ||
      nv < 0 || nf < 0)
    fail(path, tk.line(), "malformed counts line (expected 'nvertices nfaces nedges')");
  if (nv > kMaxCount || nf > kMaxCount)
    fail(path, tk.line(),
         "absurd counts " + str(counts[0]) + " " + str(counts[1]) + " (limit " + io_detail::readable_count(kMaxCount) +
             ")");
  if (nv == 0) fail(path, tk.line(), "no vertex");
  if (nf == 0) fail(path, tk.line(), "no face");
  // Every vertex needs a line "x y z" (at least 6 bytes), every face "3 a b c" (8 bytes): counts
  // the file cannot hold are rejected before anything is reserved.
  const std::uint64_t file_bytes = in.file_size();
  const double needed = 6.0 * double(nv) + 8.0 * double(nf);
  if (needed > double(file_bytes))
    fail(path, tk.line(),
         "counts announce " + io_detail::readable_count(std::uint64_t(nv)) + " vertices and " +
             io_detail::readable_count(std::uint64_t(nf)) + " faces, which need at least " +
             io_detail::readable_bytes(needed) + ", more than the " + io_detail::readable_bytes(double(file_bytes)) +
             " the file holds (truncated file?)");

  // Coordinates (24 bytes per vertex) and faces (at least 3 indices and an offset, 20 bytes).
  std::ostringstream label;
  label << "OFF file '" << path << "'";
  io_detail::check_budget(label.str(), 24.0 * double(nv) + 20.0 * double(nf),
                          io_detail::readable_count(std::uint64_t(nv)) + " vertices and " +
                              io_detail::readable_count(std::uint64_t(nf)) + " faces");
  // The counts fit the file (checked above): the positions are allocated at their size, the
  // corners as the faces come (io/detail/corner_reserve.hpp: exact for triangles only or quads only).
  PolygonMesh mesh;
  mesh.positions.resize(Eigen::Index(nv), 3);
  for (long long v = 0; v < nv; ++v) {
    if (!tk.next_line(t))
      fail(path, tk.line(), "truncated: expected " + std::to_string(nv) + " vertices, got " + std::to_string(v));
    if (t.size() < 3) fail(path, tk.line(), "vertex " + std::to_string(v) + " has fewer than 3 coordinates");
    for (int a = 0; a < 3; ++a) {
      double c = 0;
      if (!io_detail::parse_number(t[std::size_t(a)], c) || !std::isfinite(c))
        fail(path, tk.line(),
             "vertex " + std::to_string(v) + ": malformed or non-finite coordinate '" + str(t[std::size_t(a)]) + "'");
      mesh.positions(Eigen::Index(v), a) = c;
    }
  }
  io_detail::CornerReserve reserve(mesh.faces, std::size_t(nf));
  for (long long f = 0; f < nf; ++f) {
    if (!tk.next_line(t))
      fail(path, tk.line(), "truncated: expected " + std::to_string(nf) + " faces, got " + std::to_string(f));
    long long n = 0;
    if (!io_detail::parse_number(t[0], n) || n < 3)
      fail(path, tk.line(),
           "face " + std::to_string(f) + ": malformed corner count '" + str(t[0]) + "' (at least 3 needed)");
    if (std::size_t(n) + 1 > t.size())
      fail(path, tk.line(),
           "face " + std::to_string(f) + ": announces " + std::to_string(n) + " corners, line has " +
               std::to_string(t.size() - 1));
    // Each further corner needs a digit and a separator.
    const std::uint64_t rest = in.file_size() > in.offset() ? in.file_size() - in.offset() : 0;
    reserve.before_face(std::size_t(n), std::size_t(n) + std::size_t((rest + 1) / 2));
    mesh.faces.start_face();  // extra columns after the ids (colour) are ignored
    for (long long k = 0; k < n; ++k) {
      long long id = -1;
      if (!io_detail::parse_number(t[std::size_t(k + 1)], id))
        fail(path, tk.line(), "face " + std::to_string(f) + ": malformed index '" + str(t[std::size_t(k + 1)]) + "'");
      if (id < 0 || id >= nv)
        fail(path, tk.line(),
             "face " + std::to_string(f) + ": vertex index " + std::to_string(id) + " out of range (" +
                 std::to_string(nv) + " vertices)");
      mesh.faces.add_corner(int(id));
    }
  }
  return mesh;
}

PolygonMesh read_off(const std::string& path) {
  return io_detail::read_off(path, io_detail::LineReader::kDefaultBlock);
}

}  // namespace corrlap

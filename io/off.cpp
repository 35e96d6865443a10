// Object File Format (OFF) reader: "OFF" header, counts "nv nf ne", vertices, faces "n i1 .. in".
#include <algorithm>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <cstdint>
#include <fstream>
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

// Tokens of the file with their line numbers; '#' starts a comment.
class Tokens {
 public:
  Tokens(std::istream& in, const std::string& path) : in_(in), path_(path) {}
  // Next non-empty line split into tokens; false at end of file.
  bool next_line(std::vector<std::string>& toks) {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_;
      const auto hash = line.find('#');
      if (hash != std::string::npos) line.erase(hash);
      std::istringstream ls(line);
      toks.clear();
      std::string t;
      while (ls >> t) toks.push_back(t);
      if (!toks.empty()) return true;
    }
    if (in_.bad()) fail(path_, line_, "read error");
    return false;
  }
  std::size_t line() const { return line_; }

 private:
  std::istream& in_;
  const std::string& path_;
  std::size_t line_ = 0;
};

template <class T>
bool parse(const std::string& s, T& v) {
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

constexpr long long kMaxCount = 1LL << 31;

}  // namespace

PolygonMesh read_off(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, 0, "cannot open");
  Tokens tk(in, path);
  std::vector<std::string> t;
  if (!tk.next_line(t)) fail(path, 0, "empty file");
  // Header: OFF, COFF, NOFF, CNOFF...: extra per-vertex columns (colours, normals) are ignored.
  const std::string& kw = t[0];
  if (kw.size() < 3 || kw.compare(kw.size() - 3, 3, "OFF") != 0)
    fail(path, tk.line(), "not an OFF file (header '" + kw.substr(0, 40) + "', expected OFF)");
  if (kw.find("4") != std::string::npos || kw.find("n") != std::string::npos)
    fail(path, tk.line(), "unsupported OFF variant '" + kw + "' (only 3D OFF/COFF/NOFF)");
  std::vector<std::string> counts(t.begin() + 1, t.end());
  if (counts.empty() && !tk.next_line(counts)) fail(path, tk.line(), "truncated: missing the counts line");
  long long nv = 0, nf = 0;
  if (counts.size() < 2 || !parse(counts[0], nv) || !parse(counts[1], nf) || nv < 0 || nf < 0)
    fail(path, tk.line(), "malformed counts line (expected 'nvertices nfaces nedges')");
  if (nv > kMaxCount || nf > kMaxCount)
    fail(path, tk.line(),
         "absurd counts " + counts[0].substr(0, 40) + " " + counts[1].substr(0, 40) + " (limit " +
             io_detail::readable_count(kMaxCount) + ")");
  if (nv == 0) fail(path, tk.line(), "no vertex");
  if (nf == 0) fail(path, tk.line(), "no face");
  // Every vertex needs a line "x y z" (at least 6 bytes), every face "3 a b c" (8 bytes): counts
  // the file cannot hold are rejected before anything is reserved.
  const std::uint64_t file_bytes = io_detail::file_size(path);
  const double needed = 6.0 * double(nv) + 8.0 * double(nf);
  if (needed > double(file_bytes))
    fail(path, tk.line(),
         "counts announce " + io_detail::readable_count(std::uint64_t(nv)) + " vertices and " +
             io_detail::readable_count(std::uint64_t(nf)) + " faces, which need at least " +
             io_detail::readable_bytes(needed) + ", more than the " + io_detail::readable_bytes(double(file_bytes)) +
             " the file holds (truncated file?)");

  // Coordinates (24 bytes per vertex) and faces (a vector of at least 3 indices, ~40 bytes).
  std::ostringstream label;
  label << "OFF file '" << path << "'";
  io_detail::check_budget(label.str(), 24.0 * double(nv) + 40.0 * double(nf),
                          io_detail::readable_count(std::uint64_t(nv)) + " vertices and " +
                              io_detail::readable_count(std::uint64_t(nf)) + " faces");
  // Rows are added as they are read: a wrong count cannot make us allocate more than the file holds.
  std::vector<double> xyz;
  xyz.reserve(std::size_t(nv) * 3);
  for (long long v = 0; v < nv; ++v) {
    if (!tk.next_line(t))
      fail(path, tk.line(), "truncated: expected " + std::to_string(nv) + " vertices, got " + std::to_string(v));
    if (t.size() < 3) fail(path, tk.line(), "vertex " + std::to_string(v) + " has fewer than 3 coordinates");
    for (int a = 0; a < 3; ++a) {
      double c = 0;
      if (!parse(t[std::size_t(a)], c) || !std::isfinite(c))
        fail(path, tk.line(),
             "vertex " + std::to_string(v) + ": malformed or non-finite coordinate '" +
                 t[std::size_t(a)].substr(0, 40) + "'");
      xyz.push_back(c);
    }
  }
  PolygonMesh mesh;
  mesh.positions =
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(xyz.data(), Eigen::Index(nv), 3);
  mesh.faces.reserve(std::size_t(nf));
  for (long long f = 0; f < nf; ++f) {
    if (!tk.next_line(t))
      fail(path, tk.line(), "truncated: expected " + std::to_string(nf) + " faces, got " + std::to_string(f));
    long long n = 0;
    if (!parse(t[0], n) || n < 3)
      fail(path, tk.line(),
           "face " + std::to_string(f) + ": malformed corner count '" + t[0].substr(0, 40) + "' (at least 3 needed)");
    if (std::size_t(n) + 1 > t.size())
      fail(path, tk.line(),
           "face " + std::to_string(f) + ": announces " + std::to_string(n) + " corners, line has " +
               std::to_string(t.size() - 1));
    std::vector<int> ids(static_cast<std::size_t>(n));
    for (long long k = 0; k < n; ++k) {
      long long id = -1;
      if (!parse(t[std::size_t(k + 1)], id))
        fail(path, tk.line(),
             "face " + std::to_string(f) + ": malformed index '" + t[std::size_t(k + 1)].substr(0, 40) + "'");
      if (id < 0 || id >= nv)
        fail(path, tk.line(),
             "face " + std::to_string(f) + ": vertex index " + std::to_string(id) + " out of range (" +
                 std::to_string(nv) + " vertices)");
      ids[std::size_t(k)] = int(id);
    }
    mesh.faces.push_back(std::move(ids));  // extra columns after the ids (colour) are ignored
  }
  return mesh;
}

}  // namespace corrlap

#include "text_io.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

namespace corrlap {

namespace {
// Reads rows of exactly `cols` finite numbers.
std::vector<double> read_rows(const std::string& path, int cols, const char* what) {
  std::ifstream in(path);
  if (!in) throw IoError(std::string(what) + " file '" + path + "': cannot open");
  std::vector<double> values;
  std::string line;
  std::size_t lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream ls(line);
    std::string tok;
    int n = 0;
    while (ls >> tok) {
      double v = 0;
      auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (ec != std::errc() || p != tok.data() + tok.size() || !std::isfinite(v)) {
        std::ostringstream os;
        os << what << " file '" << path << "', line " << lineno << ": malformed or non-finite number '"
           << tok.substr(0, 40) << "'";
        throw IoError(os.str());
      }
      values.push_back(v);
      ++n;
    }
    if (n != 0 && n != cols) {
      std::ostringstream os;
      os << what << " file '" << path << "', line " << lineno << ": expected " << cols << " numbers, got " << n;
      throw IoError(os.str());
    }
  }
  if (values.empty()) throw IoError(std::string(what) + " file '" + path + "': no data (empty file)");
  return values;
}

// Exactly three whitespace-separated numbers (trailing '\r' allowed), nothing else on the line.
template <class A, class B, class C>
bool parse_numbers(const std::string& line, A& a, B& b, C& c) {
  std::istringstream ls(line);
  std::string t[3], extra;
  if (!(ls >> t[0] >> t[1] >> t[2]) || (ls >> extra)) return false;
  auto one = [](const std::string& s, auto& v) {
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return ec == std::errc() && p == s.data() + s.size();
  };
  return one(t[0], a) && one(t[1], b) && one(t[2], c);
}
}  // namespace

Eigen::MatrixX3d read_normals(const std::string& path) {
  std::vector<double> v = read_rows(path, 3, "normals");
  return Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(v.data(), Eigen::Index(v.size() / 3), 3);
}

void write_normals(const std::string& path, const Eigen::MatrixX3d& n) {
  for (Eigen::Index i = 0; i < n.rows(); ++i)
    for (int c = 0; c < 3; ++c) io_detail::require_finite(n(i, c), path, "normals", "row", (long long)i + 1);
  io_detail::OutputFile f(path, "normals");
  for (Eigen::Index i = 0; i < n.rows(); ++i) std::fprintf(f.get(), "%.17g %.17g %.17g\n", n(i, 0), n(i, 1), n(i, 2));
  f.commit();
}

Eigen::VectorXd read_scalars(const std::string& path) {
  std::vector<double> v = read_rows(path, 1, "scalars");
  return Eigen::Map<Eigen::VectorXd>(v.data(), Eigen::Index(v.size()));
}

void write_scalars(const std::string& path, const Eigen::VectorXd& values) {
  for (Eigen::Index i = 0; i < values.size(); ++i)
    io_detail::require_finite(values[i], path, "scalars", "row", (long long)i + 1);
  io_detail::OutputFile f(path, "scalars");
  for (Eigen::Index i = 0; i < values.size(); ++i) std::fprintf(f.get(), "%.17g\n", values[i]);
  f.commit();
}

void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& A) {
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k)
    io_detail::require_finite(A.valuePtr()[k], path, "Matrix Market", "stored entry", (long long)k + 1);
  io_detail::OutputFile f(path, "Matrix Market");
  std::fprintf(f.get(), "%%%%MatrixMarket matrix coordinate real general\n%% written by corrlap\n");
  std::fprintf(f.get(), "%lld %lld %lld\n", (long long)A.rows(), (long long)A.cols(), (long long)A.nonZeros());
  for (Eigen::Index c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it)
      std::fprintf(f.get(), "%lld %lld %.17g\n", (long long)it.row() + 1, (long long)it.col() + 1, it.value());
  f.commit();
}

Eigen::SparseMatrix<double> read_matrix_market(const std::string& path) {
  using io_detail::readable_count;
  auto fail = [&](const std::string& what) -> void { throw IoError("Matrix Market file '" + path + "': " + what); };
  std::ifstream in(path);
  if (!in) fail("cannot open");
  const std::uint64_t file_bytes = io_detail::bytes_left(in);
  std::string header;
  if (!std::getline(in, header)) fail("missing %%MatrixMarket header (empty file)");
  // Banner: %%MatrixMarket matrix coordinate real|integer|pattern general|symmetric (fields are
  // case-insensitive; each must be one word, matched exactly, not found anywhere in the line).
  std::vector<std::string> banner;
  {
    std::istringstream hs(header);
    std::string w;
    while (hs >> w) {
      std::transform(w.begin(), w.end(), w.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
      banner.push_back(w);
    }
  }
  const std::string shown = header.substr(0, 80);
  if (banner.empty() || banner[0] != "%%matrixmarket")
    fail("missing %%MatrixMarket header (first line '" + shown + "')");
  if (banner.size() != 5 || banner[1] != "matrix")
    fail("malformed header '" + shown + "' (expected '%%MatrixMarket matrix coordinate real general')");
  if (banner[2] != "coordinate" || (banner[3] != "real" && banner[3] != "integer" && banner[3] != "pattern"))
    fail("header '" + shown + "': only real coordinate matrices are supported (coordinate real|integer|pattern)");
  if (banner[4] != "general" && banner[4] != "symmetric")
    fail("header '" + shown + "': unsupported symmetry '" + banner[4] + "' (general or symmetric)");
  const bool symmetric = banner[4] == "symmetric", pattern = banner[3] == "pattern";
  std::string line;
  std::size_t lineno = 1;
  bool have_size = false;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") != std::string::npos && line[0] != '%') {
      have_size = true;
      break;
    }
  }
  long long r = 0, c = 0, nnz = 0;
  if (!have_size || !parse_numbers(line, r, c, nnz) || r <= 0 || c <= 0 || nnz < 0)
    fail("line " + std::to_string(lineno) + ": malformed size line '" + line.substr(0, 80) +
         "' (expected 'rows columns entries')");
  const std::string size_at = "line " + std::to_string(lineno) + ": ";
  if (symmetric && r != c)
    fail(size_at + "a symmetric matrix must be square, the size line declares " + readable_count(std::uint64_t(r)) +
         " x " + readable_count(std::uint64_t(c)));
  // Budget before allocating: every entry needs a line of at least "i j v\n" (6 bytes, 4 for
  // pattern), and Eigen allocates O(rows + columns) index arrays however few the entries, so
  // each dimension is bounded by max(2^20, 4 * entries) (every row and column of the operators
  // holds an entry) and by the int indices Eigen uses.
  const std::uint64_t min_line = pattern ? 4 : 6;
  if (double(nnz) > double(r) * double(c))
    fail(size_at + "absurd size line: " + readable_count(std::uint64_t(nnz)) + " entries in a " +
         readable_count(std::uint64_t(r)) + " x " + readable_count(std::uint64_t(c)) + " matrix");
  if (std::uint64_t(nnz) > file_bytes / min_line)
    fail(size_at + "absurd size line: " + readable_count(std::uint64_t(nnz)) + " entries need at least " +
         io_detail::readable_bytes(double(nnz) * double(min_line)) + ", more than the " +
         io_detail::readable_bytes(double(file_bytes)) + " the file holds");
  const long long dim_limit = std::min<long long>(std::numeric_limits<int>::max() - 1, std::max(1LL << 20, 4 * nnz));
  if (r > dim_limit || c > dim_limit)
    fail(size_at + "absurd size line: " + readable_count(std::uint64_t(r)) + " x " + readable_count(std::uint64_t(c)) +
         " for " + readable_count(std::uint64_t(nnz)) +
         " entries (each dimension is limited to max(1 048 576, 4 x entries) = " +
         readable_count(std::uint64_t(dim_limit)) + ")");
  // Triplets (16 bytes each, twice for symmetric files) and the compressed matrix (12 bytes per entry).
  const double stored = double(nnz) * (symmetric ? 2.0 : 1.0);
  io_detail::check_budget("Matrix Market file '" + path + "'", stored * 28.0 + 8.0 * double(c),
                          readable_count(std::uint64_t(nnz)) + " entries");
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(std::size_t(nnz) * (symmetric ? 2 : 1));
  for (long long k = 0; k < nnz; ++k) {
    long long i = 0, j = 0;
    double v = 1.0;
    std::string extra;
    ++lineno;
    auto entry = [&] { return "line " + std::to_string(lineno) + ", entry " + std::to_string(k + 1); };
    if (!std::getline(in, line))
      fail(entry() + ": truncated: end of file after " + readable_count(std::uint64_t(k)) + " of " +
           readable_count(std::uint64_t(nnz)) + " declared entries");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    bool ok = true;
    if (pattern) {
      std::istringstream ls(line);
      std::string a, b;
      ok = (ls >> a >> b) && !(ls >> extra) && parse_numbers(a + " " + b + " 1", i, j, v);
    } else {
      ok = parse_numbers(line, i, j, v);
    }
    if (!ok)
      fail(entry() + ": malformed entry '" + line.substr(0, 80) + "' (expected '" +
           (pattern ? "row column" : "row column value") + "')");
    if (i < 1 || i > r || j < 1 || j > c)
      fail(entry() + ": index (" + std::to_string(i) + ", " + std::to_string(j) + ") out of range for a " +
           readable_count(std::uint64_t(r)) + " x " + readable_count(std::uint64_t(c)) + " matrix");
    if (!std::isfinite(v)) fail(entry() + ": value not finite");
    if (symmetric && j > i)
      fail(entry() + ": (" + std::to_string(i) + ", " + std::to_string(j) +
           ") is above the diagonal; a symmetric file stores the lower triangle");
    t.emplace_back(int(i - 1), int(j - 1), v);
    if (symmetric && i != j) t.emplace_back(int(j - 1), int(i - 1), v);
  }
  while (std::getline(in, line)) {
    ++lineno;
    if (line.find_first_not_of(" \t\r") != std::string::npos)
      fail("line " + std::to_string(lineno) + ": more entries than the " + readable_count(std::uint64_t(nnz)) +
           " declared");
  }
  Eigen::SparseMatrix<double> A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace corrlap

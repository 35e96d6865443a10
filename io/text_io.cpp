#include "text_io.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/block_readers.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/line_reader.hpp>
#include <corrlap/io/detail/mesh_records.hpp>
#include <corrlap/io/detail/text_writer.hpp>
#include <corrlap/io/detail/tokens.hpp>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

namespace corrlap {

namespace {
// Rows of exactly `cols` finite numbers (blank lines and # comments skipped) into Out (a matrix
// with `cols` columns). A first pass counts the rows, so that the result is allocated once, at its
// size, and parsed into directly.
template <class Out>
Out read_rows(const std::string& path, int cols, const char* what) {
  io_detail::LineReader in(path);
  if (!in.is_open()) throw IoError(std::string(what) + " file '" + path + "': cannot open");
  auto data_of = [](std::string_view line) { return line.substr(0, line.find('#')); };
  std::size_t rows = 0;
  std::string_view line, tok;
  while (in.next(line))
    if (io_detail::Tokens(data_of(line)).more()) ++rows;
  if (in.error()) throw IoError(std::string(what) + " file '" + path + "': read error");
  if (rows == 0) throw IoError(std::string(what) + " file '" + path + "': no data (empty file)");
  io_detail::check_budget(std::string(what) + " file '" + path + "'", 8.0 * double(rows) * cols,
                          io_detail::readable_count(rows) + " rows");
  Out out(Eigen::Index(rows), cols);
  in.rewind();
  std::size_t row = 0;
  while (in.next(line)) {
    io_detail::Tokens ls(data_of(line));
    int n = 0;
    while (ls.next(tok)) {
      double v = 0;
      if (!io_detail::parse_number(tok, v) || !std::isfinite(v)) {
        std::ostringstream os;
        os << what << " file '" << path << "', line " << in.line_number() << ": malformed or non-finite number '"
           << tok.substr(0, 40) << "'";
        throw IoError(os.str());
      }
      if (n < cols && row < rows) out(Eigen::Index(row), n) = v;
      ++n;
    }
    if (n != 0 && n != cols) {
      std::ostringstream os;
      os << what << " file '" << path << "', line " << in.line_number() << ": expected " << cols << " numbers, got "
         << n;
      throw IoError(os.str());
    }
    if (n != 0 && ++row > rows) throw IoError(std::string(what) + " file '" + path + "': file changed while reading");
  }
  if (row != rows) throw IoError(std::string(what) + " file '" + path + "': file changed while reading");
  return out;
}

// Exactly three whitespace-separated numbers (a trailing '\r' allowed), nothing else on the line.
template <class A, class B, class C>
bool parse_numbers(std::string_view line, A& a, B& b, C& c) {
  io_detail::Tokens ls(line);
  std::string_view t[3];
  if (!ls.next(t[0]) || !ls.next(t[1]) || !ls.next(t[2]) || ls.more()) return false;
  return io_detail::parse_number(t[0], a) && io_detail::parse_number(t[1], b) && io_detail::parse_number(t[2], c);
}

// Replaces the entries of `parsed` (rows and values in its storage, in file order, and their
// columns) by the compressed matrix they make: a counting sort by column, then rows sorted within
// each column and repeated entries summed in file order, as setFromTriplets would, without its
// triplets and transposed copy. A symmetric file's entries below the diagonal are mirrored above.
// (In place: Eigen 3.4's SparseMatrix has no move constructor, a returned matrix is copied.)
void by_columns(Eigen::SparseMatrix<double>& parsed, std::vector<int>& columns, bool symmetric) {
  const Eigen::Index cols = parsed.cols();
  const std::size_t n = columns.size();
  const int* rows = parsed.innerIndexPtr();
  const double* values = parsed.valuePtr();
  Eigen::SparseMatrix<double> A(parsed.rows(), cols);
  int* outer = A.outerIndexPtr();  // counts per column, then their starts
  for (std::size_t k = 0; k < n; ++k) {
    ++outer[columns[k] + 1];
    if (symmetric && rows[k] != columns[k]) ++outer[rows[k] + 1];
  }
  for (Eigen::Index j = 0; j < cols; ++j) outer[j + 1] += outer[j];
  A.resizeNonZeros(outer[cols]);
  int* out_rows = A.innerIndexPtr();
  double* out_values = A.valuePtr();
  {
    std::vector<int> next(outer, outer + cols);
    for (std::size_t k = 0; k < n; ++k) {
      const int at = next[std::size_t(columns[k])]++;
      out_rows[at] = rows[k];
      out_values[at] = values[k];
      if (symmetric && rows[k] != columns[k]) {
        const int mirrored = next[std::size_t(rows[k])]++;
        out_rows[mirrored] = columns[k];
        out_values[mirrored] = values[k];
      }
    }
  }
  columns = {};
  // Sort each column by row (stable: repeats keep the file order) and sum repeats, compacting.
  std::vector<std::pair<int, double>> column;
  int kept = 0;
  for (Eigen::Index j = 0; j < cols; ++j) {
    const int b = outer[j], e = outer[j + 1];
    outer[j] = kept;
    if (!std::is_sorted(out_rows + b, out_rows + e)) {
      column.clear();
      for (int k = b; k < e; ++k) column.emplace_back(out_rows[k], out_values[k]);
      std::stable_sort(column.begin(), column.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
      for (int k = b; k < e; ++k) std::tie(out_rows[k], out_values[k]) = column[std::size_t(k - b)];
    }
    for (int k = b; k < e; ++k) {
      if (kept > outer[j] && out_rows[kept - 1] == out_rows[k]) {
        out_values[kept - 1] += out_values[k];
      } else {
        out_rows[kept] = out_rows[k];
        out_values[kept] = out_values[k];
        ++kept;
      }
    }
  }
  outer[cols] = kept;
  A.resizeNonZeros(kept);
  parsed.swap(A);
}
}  // namespace

Eigen::MatrixX3d read_normals(const std::string& path) { return read_rows<Eigen::MatrixX3d>(path, 3, "normals"); }

void write_normals(const std::string& path, const Eigen::MatrixX3d& n) {
  for (Eigen::Index i = 0; i < n.rows(); ++i)
    for (int c = 0; c < 3; ++c) io_detail::require_finite(n(i, c), path, "normals", "row", (long long)i + 1);
  io_detail::TextWriter out(path, "normals");
  for (Eigen::Index i = 0; i < n.rows(); ++i) {
    out.write_double(n(i, 0));
    out.write(' ');
    out.write_double(n(i, 1));
    out.write(' ');
    out.write_double(n(i, 2));
    out.write('\n');
  }
  out.commit();
}

Eigen::VectorXd read_scalars(const std::string& path) { return read_rows<Eigen::VectorXd>(path, 1, "scalars"); }

void write_scalars(const std::string& path, const Eigen::VectorXd& values, const std::vector<std::string>& comments) {
  for (Eigen::Index i = 0; i < values.size(); ++i)
    io_detail::require_finite(values[i], path, "scalars", "row", (long long)i + 1);
  io_detail::TextWriter out(path, "scalars");
  out.write(scalars_file_header(comments));
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    out.write_double(values[i]);
    out.write('\n');
  }
  out.commit();
}

std::string scalars_file_header(const std::vector<std::string>& comments) {
  std::string out;
  for (const std::string& c : comments) {
    out += "# ";
    for (const char ch : c) out += ch == '\n' || ch == '\r' ? ' ' : ch;  // one line each
    out += '\n';
  }
  return out;
}

std::string scalars_file_rows(const std::string& path, const Eigen::VectorXd& values, std::int64_t first) {
  for (Eigen::Index i = 0; i < values.size(); ++i)
    io_detail::require_finite(values[i], path, "scalars", "row", (long long)(first + i) + 1);
  std::string out;
  io_detail::StringSink sink(out);
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    sink.write_double(values[i]);
    sink.write('\n');
  }
  return out;
}

void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& A) {
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k)
    io_detail::require_finite(A.valuePtr()[k], path, "Matrix Market", "stored entry", (long long)k + 1);
  io_detail::TextWriter out(path, "Matrix Market");
  out.write("%%MatrixMarket matrix coordinate real general\n% written by corrlap\n");
  out.write_int(A.rows());
  out.write(' ');
  out.write_int(A.cols());
  out.write(' ');
  out.write_int(A.nonZeros());
  out.write('\n');
  for (Eigen::Index c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) {
      out.write_int(it.row() + 1);
      out.write(' ');
      out.write_int(it.col() + 1);
      out.write(' ');
      out.write_double(it.value());
      out.write('\n');
    }
  out.commit();
}

Eigen::SparseMatrix<double> io_detail::read_matrix_market(const std::string& path, std::size_t block_bytes) {
  using io_detail::readable_count;
  auto fail = [&](const std::string& what) -> void { throw IoError("Matrix Market file '" + path + "': " + what); };
  io_detail::LineReader in(path, block_bytes);
  if (!in.is_open()) fail("cannot open");
  const std::uint64_t file_bytes = in.file_size();
  std::string_view header_line;
  if (!in.next(header_line)) fail("missing %%MatrixMarket header (empty file)");
  const std::string header(header_line);
  // Banner: %%MatrixMarket matrix coordinate real|integer|pattern general|symmetric (fields are
  // case-insensitive; each must be one word, matched exactly, not found anywhere in the line).
  std::vector<std::string> banner;
  {
    io_detail::Tokens hs(header);
    std::string_view word;
    while (hs.next(word)) {
      std::string w(word);
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
  std::string_view line;
  std::size_t lineno = 1;
  bool have_size = false;
  while (in.next(line)) {
    ++lineno;
    line = io_detail::without_cr(line);
    if (line.find_first_not_of(" \t") != std::string_view::npos && line[0] != '%') {
      have_size = true;
      break;
    }
  }
  if (!have_size) line = {};
  long long r = 0, c = 0, nnz = 0;
  if (!have_size || !parse_numbers(line, r, c, nnz) || r <= 0 || c <= 0 || nnz < 0)
    fail("line " + std::to_string(lineno) + ": malformed size line '" + std::string(line.substr(0, 80)) +
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
  // At most: the entries as parsed (rows, values, columns: 16 bytes each) and the compressed matrix they
  // are sorted into (12 bytes per stored entry, twice as many for symmetric files); rounded up.
  const double stored = double(nnz) * (symmetric ? 2.0 : 1.0);
  io_detail::check_budget("Matrix Market file '" + path + "'", stored * 28.0 + 8.0 * double(c),
                          readable_count(std::uint64_t(nnz)) + " entries");
  // Entries are parsed straight into the compressed storage of the result, rows and values in
  // place. While the file is sorted by column, then row, without repeats (what write_matrix_market
  // writes), the column starts are set as the columns come and nothing else is held. From the
  // first entry out of that order on (at once for symmetric files) every entry's column is kept and
  // the entries are sorted into a second matrix at the end (by_columns).
  Eigen::SparseMatrix<double> A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
  A.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* rows = A.innerIndexPtr();
  double* values = A.valuePtr();
  int* outer = A.outerIndexPtr();
  bool sorted = !symmetric;
  std::vector<int> columns(sorted ? 0 : std::size_t(nnz));
  int last = -1;  // sorted: the column of the last entry; outer[0..last] are set
  for (long long k = 0; k < nnz; ++k) {
    long long i = 0, j = 0;
    double v = 1.0;
    ++lineno;
    auto entry = [&] { return "line " + std::to_string(lineno) + ", entry " + std::to_string(k + 1); };
    if (!in.next(line))
      fail(entry() + ": truncated: end of file after " + readable_count(std::uint64_t(k)) + " of " +
           readable_count(std::uint64_t(nnz)) + " declared entries");
    line = io_detail::without_cr(line);
    bool ok = true;
    if (pattern) {
      io_detail::Tokens ls(line);
      std::string_view a, b;
      ok = ls.next(a) && ls.next(b) && !ls.more() && io_detail::parse_number(a, i) && io_detail::parse_number(b, j);
    } else {
      ok = parse_numbers(line, i, j, v);
    }
    if (!ok)
      fail(entry() + ": malformed entry '" + std::string(line.substr(0, 80)) + "' (expected '" +
           (pattern ? "row column" : "row column value") + "')");
    if (i < 1 || i > r || j < 1 || j > c)
      fail(entry() + ": index (" + std::to_string(i) + ", " + std::to_string(j) + ") out of range for a " +
           readable_count(std::uint64_t(r)) + " x " + readable_count(std::uint64_t(c)) + " matrix");
    if (!std::isfinite(v)) fail(entry() + ": value not finite");
    if (symmetric && j > i)
      fail(entry() + ": (" + std::to_string(i) + ", " + std::to_string(j) +
           ") is above the diagonal; a symmetric file stores the lower triangle");
    const auto kk = std::size_t(k);
    const int row = int(i - 1), col = int(j - 1);
    if (sorted && col > last) {
      std::fill(outer + last + 1, outer + col + 1, int(k));
      last = col;
    } else if (sorted && (col < last || row <= rows[kk - 1])) {
      sorted = false;  // the columns of the entries so far, from the column starts
      columns.resize(std::size_t(nnz));
      for (int q = 0; q <= last; ++q)
        std::fill(columns.begin() + outer[q], columns.begin() + (q < last ? outer[q + 1] : int(k)), q);
    }
    if (!sorted) columns[kk] = col;
    rows[kk] = row;
    values[kk] = v;
  }
  while (in.next(line)) {
    ++lineno;
    if (line.find_first_not_of(" \t\r") != std::string_view::npos)
      fail("line " + std::to_string(lineno) + ": more entries than the " + readable_count(std::uint64_t(nnz)) +
           " declared");
  }
  if (in.error()) fail("read error");
  if (sorted)
    std::fill(outer + last + 1, outer + c + 1, int(nnz));
  else
    by_columns(A, columns, symmetric);
  return A;
}

Eigen::SparseMatrix<double> read_matrix_market(const std::string& path) {
  return io_detail::read_matrix_market(path, io_detail::LineReader::kDefaultBlock);
}

}  // namespace corrlap

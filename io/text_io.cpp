#include "text_io.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

namespace corrlap {

namespace {
using File = std::unique_ptr<FILE, int (*)(FILE*)>;

File open_for_writing(const std::string& path, const char* what) {
  File f(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!f) throw IoError(std::string(what) + " file '" + path + "': cannot open for writing: " + std::strerror(errno));
  return f;
}

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
        os << what << " file '" << path << "', line " << lineno << ": malformed or non-finite number '" << tok << "'";
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
  File f = open_for_writing(path, "normals");
  for (Eigen::Index i = 0; i < n.rows(); ++i) std::fprintf(f.get(), "%.17g %.17g %.17g\n", n(i, 0), n(i, 1), n(i, 2));
  if (std::ferror(f.get())) throw IoError("normals file '" + path + "': write error");
}

Eigen::VectorXd read_scalars(const std::string& path) {
  std::vector<double> v = read_rows(path, 1, "scalars");
  return Eigen::Map<Eigen::VectorXd>(v.data(), Eigen::Index(v.size()));
}

void write_scalars(const std::string& path, const Eigen::VectorXd& values) {
  File f = open_for_writing(path, "scalars");
  for (Eigen::Index i = 0; i < values.size(); ++i) std::fprintf(f.get(), "%.17g\n", values[i]);
  if (std::ferror(f.get())) throw IoError("scalars file '" + path + "': write error");
}

void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& A) {
  File f = open_for_writing(path, "Matrix Market");
  std::fprintf(f.get(), "%%%%MatrixMarket matrix coordinate real general\n%% written by corrlap\n");
  std::fprintf(f.get(), "%lld %lld %lld\n", (long long)A.rows(), (long long)A.cols(), (long long)A.nonZeros());
  for (Eigen::Index c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it)
      std::fprintf(f.get(), "%lld %lld %.17g\n", (long long)it.row() + 1, (long long)it.col() + 1, it.value());
  if (std::ferror(f.get())) throw IoError("Matrix Market file '" + path + "': write error");
}

Eigen::SparseMatrix<double> read_matrix_market(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("Matrix Market file '" + path + "': cannot open");
  std::string header;
  if (!std::getline(in, header) || header.rfind("%%MatrixMarket", 0) != 0)
    throw IoError("Matrix Market file '" + path + "': missing %%MatrixMarket header");
  const bool symmetric = header.find("symmetric") != std::string::npos;
  if (header.find("coordinate") == std::string::npos || header.find("complex") != std::string::npos)
    throw IoError("Matrix Market file '" + path + "': only real coordinate matrices are supported");
  std::string line;
  while (std::getline(in, line) && (line.empty() || line[0] == '%')) {
  }
  long long r = 0, c = 0, nnz = 0;
  if (!parse_numbers(line, r, c, nnz) || r <= 0 || c <= 0 || nnz < 0)
    throw IoError("Matrix Market file '" + path + "': malformed size line '" + line.substr(0, 80) + "'");
  // 2^27 rows/columns is far beyond any surface this tool handles; larger is a corrupt file (the
  // column pointer array alone would take gigabytes).
  if (r > (1LL << 27) || c > (1LL << 27) || nnz > (1LL << 34) || double(nnz) > double(r) * double(c))
    throw IoError("Matrix Market file '" + path + "': absurd size line '" + line.substr(0, 80) + "'");
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(std::size_t(std::min<long long>(nnz, 1LL << 26)));
  for (long long k = 0; k < nnz; ++k) {
    long long i = 0, j = 0;
    double v = 0;
    if (!std::getline(in, line) || !parse_numbers(line, i, j, v))
      throw IoError("Matrix Market file '" + path + "': truncated or malformed entry " + std::to_string(k + 1));
    if (i < 1 || i > r || j < 1 || j > c || !std::isfinite(v))
      throw IoError("Matrix Market file '" + path + "': entry " + std::to_string(k + 1) +
                    " out of range or not finite");
    t.emplace_back(int(i - 1), int(j - 1), v);
    if (symmetric && i != j) t.emplace_back(int(j - 1), int(i - 1), v);
  }
  Eigen::SparseMatrix<double> A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace corrlap

#include "solver_support.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace corrlap::detail {

void check_matrix(const Eigen::SparseMatrix<double>& A, const std::string& solver, bool check_symmetry) {
  if (A.rows() != A.cols() || A.rows() == 0) {
    std::ostringstream os;
    os << solver << ": matrix must be square and non-empty, got " << A.rows() << " x " << A.cols();
    throw SolverError(SolverStatus::InvalidInput, os.str());
  }
  for (Eigen::Index j = 0; j < A.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it)
      if (!std::isfinite(it.value())) {
        std::ostringstream os;
        os << solver << ": matrix entry (" << it.row() << ", " << it.col() << ") is " << it.value();
        throw SolverError(SolverStatus::NumericalIssue, os.str());
      }
  if (check_symmetry) {
    // A copy-free check: the heat kernel's matrices have ~2000 entries per row, and forming A^T
    // and A - A^T doubled the memory of a solve (bench/RESULTS.md, "corrlap study").
    const double norm = A.norm();
    const double diff = symmetry_defect(A);
    if (diff > 1e-10 * norm) {
      std::ostringstream os;
      os << solver << ": matrix is not symmetric (|A - A^T| / |A| = " << diff / norm << ")";
      throw SolverError(SolverStatus::InvalidInput, os.str());
    }
  }
}

double symmetry_defect(const Eigen::SparseMatrix<double>& A) {
  if (A.rows() != A.cols()) return std::numeric_limits<double>::infinity();
  if (!A.isCompressed()) {
    Eigen::SparseMatrix<double> compressed = A;
    compressed.makeCompressed();
    return symmetry_defect(compressed);
  }
  const Eigen::Index n = A.outerSize();
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* value = A.valuePtr();
  // Columns in ascending order j: the mirrors (j, i) of the lower entries (i, j), i > j, are the
  // upper entries of column i, met in ascending row order j. A cursor per column walks its upper
  // part: entries it skips have no mirror.
  std::vector<int> cursor(outer, outer + n);
  double sum = 0;
  for (Eigen::Index j = 0; j < n; ++j)
    for (int k = outer[j]; k < outer[j + 1]; ++k) {
      const int i = inner[k];
      if (i <= int(j)) continue;  // the upper part is met through the cursors
      int& c = cursor[std::size_t(i)];
      for (; c < outer[i + 1] && inner[c] < int(j); ++c) sum += 2.0 * value[c] * value[c];
      if (c < outer[i + 1] && inner[c] == int(j)) {
        const double d = value[k] - value[c];
        sum += 2.0 * d * d;  // (i, j) and (j, i)
        ++c;
      } else {
        sum += 2.0 * value[k] * value[k];  // (i, j) without mirror
      }
    }
  // Upper entries the cursors did not reach (rows < i, unmatched).
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = cursor[std::size_t(i)]; c < outer[i + 1] && inner[c] < int(i); ++c) sum += 2.0 * value[c] * value[c];
  return std::sqrt(sum);
}

void check_rhs(const Eigen::MatrixXd& B, Eigen::Index n, const std::string& solver) {
  if (B.rows() != n) {
    std::ostringstream os;
    os << solver << ": right-hand side has " << B.rows() << " rows, the factored matrix has " << n;
    throw SolverError(SolverStatus::InvalidInput, os.str());
  }
  for (Eigen::Index j = 0; j < B.cols(); ++j)
    for (Eigen::Index i = 0; i < B.rows(); ++i)
      if (!std::isfinite(B(i, j))) {
        std::ostringstream os;
        os << solver << ": right-hand side entry (" << i << ", " << j << ") is " << B(i, j);
        throw SolverError(SolverStatus::NumericalIssue, os.str());
      }
}

void Pattern::assign(const Eigen::SparseMatrix<double>& A) {
  Eigen::SparseMatrix<double> C;
  const Eigen::SparseMatrix<double>* a = &A;
  if (!A.isCompressed()) {
    C = A;
    C.makeCompressed();
    a = &C;
  }
  rows = a->rows();
  outer.assign(a->outerIndexPtr(), a->outerIndexPtr() + a->outerSize() + 1);
  inner.assign(a->innerIndexPtr(), a->innerIndexPtr() + a->nonZeros());
}

bool Pattern::matches(const Eigen::SparseMatrix<double>& A) const {
  if (A.isCompressed()) {  // no copy on the refactorization path
    if (A.rows() != rows || A.cols() != rows || std::size_t(A.nonZeros()) != inner.size()) return false;
    return std::equal(outer.begin(), outer.end(), A.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), A.innerIndexPtr());
  }
  Pattern other;
  other.assign(A);
  return other.rows == rows && other.outer == outer && other.inner == inner;
}

void check_same_pattern(const Pattern& analyzed, const Eigen::SparseMatrix<double>& A, const std::string& solver) {
  if (analyzed.empty()) throw SolverError(SolverStatus::NotAnalyzed, solver + ": factorize() called before analyze()");
  if (!analyzed.matches(A)) {
    std::ostringstream os;
    os << solver << ": factorize() got a matrix (" << A.rows() << " x " << A.cols() << ", " << A.nonZeros()
       << " nonzeros) whose sparsity pattern differs from the analyzed one (" << analyzed.rows << " x " << analyzed.rows
       << ", " << analyzed.inner.size() << " nonzeros); call analyze() again";
    throw SolverError(SolverStatus::InvalidInput, os.str());
  }
}

std::vector<std::string> allowed_keys(const std::vector<ParameterInfo>& options) {
  std::vector<std::string> keys{"solver"};
  for (const auto& o : options) keys.push_back(o.name);
  return keys;
}

Config without_keys(const Config& config, const std::vector<std::string>& drop) {
  std::vector<std::string> items;
  for (const auto& k : config.keys())
    if (std::find(drop.begin(), drop.end(), k) == drop.end()) items.push_back(k + "=" + config.get_string(k, ""));
  return Config::from_key_values(items);
}

double relative_residual(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& X, const Eigen::MatrixXd& B) {
  const double nb = B.norm();
  const double nr = (A * X - B).norm();
  return nb > 0 ? nr / nb : nr;
}

}  // namespace corrlap::detail

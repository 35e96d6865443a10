#include "laplacian_regularization.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <sstream>
#include <string>

namespace corrlap {

namespace {

void check_inputs(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, const Eigen::MatrixX3d& p,
                  const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H) {
  const Eigen::Index n = p.rows();
  const auto size_error = [&](const std::string& what, Eigen::Index rows, Eigen::Index cols) {
    std::ostringstream os;
    os << "regularization: " << what << " is " << rows << " x " << cols << ", expected " << n << " x "
       << (what == "H"         ? 1
           : what == "normals" ? 3
                               : n)
       << " (one row per vertex)";
    throw InputError(os.str());
  };
  if (n == 0) throw InputError("regularization: the surface has no vertex");
  if (L.rows() != n || L.cols() != n) size_error("L", L.rows(), L.cols());
  if (M.rows() != n || M.cols() != n) size_error("M", M.rows(), M.cols());
  if (normals.rows() != n) size_error("normals", normals.rows(), normals.cols());
  if (H.size() != n) size_error("H", H.size(), 1);
  if (!p.allFinite()) throw InputError("regularization: a vertex position is not finite");
  for (Eigen::Index v = 0; v < n; ++v) {
    if (!std::isfinite(H[v])) {
      std::ostringstream os;
      os << "regularization: the mean curvature of vertex " << v << " is " << H[v];
      throw InputError(os.str());
    }
    if (!normals.row(v).allFinite() || std::abs(normals.row(v).norm() - 1.0) > 1e-6) {
      std::ostringstream os;
      os << "regularization: the normal of vertex " << v << " is not a unit vector (" << normals.row(v) << ")";
      throw InputError(os.str());
    }
  }
}

// The rows H_v n_v^T.
Eigen::MatrixX3d mean_curvature_normals(const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H) {
  return H.asDiagonal() * normals;
}

}  // namespace

Eigen::SparseMatrix<double> lumped_mass(const Eigen::SparseMatrix<double>& M) {
  const Eigen::VectorXd row_sums = M * Eigen::VectorXd::Ones(M.cols());
  Eigen::SparseMatrix<double> Ml(M.rows(), M.cols());
  Ml.reserve(Eigen::VectorXi::Constant(M.cols(), 1));
  for (Eigen::Index v = 0; v < row_sums.size(); ++v) {
    if (!(row_sums[v] > 0.0) || !std::isfinite(row_sums[v])) {
      std::ostringstream os;
      os << "lumped mass: vertex " << v << " has mass " << row_sums[v] << " (must be positive)";
      throw InputError(os.str());
    }
    Ml.insert(v, v) = row_sums[v];
  }
  Ml.makeCompressed();
  return Ml;
}

double regularization_alpha(double h, double alpha0) {
  if (!(h > 0.0) || !std::isfinite(h)) throw InputError("regularization: h must be a positive number");
  if (!(alpha0 > 0.0) || !std::isfinite(alpha0)) throw InputError("regularization: alpha0 must be a positive number");
  return alpha0 / (h * h);
}

Eigen::MatrixX3d regularize_positions(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                      const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                      const Eigen::VectorXd& H, double alpha, LinearSolver& solver) {
  check_inputs(L, M, p, normals, H);
  if (!(alpha > 0.0) || !std::isfinite(alpha)) throw InputError("regularization: alpha must be a positive number");
  const Eigen::SparseMatrix<double> Ml = lumped_mass(M);
  const Eigen::VectorXd inverse_mass = Ml.diagonal().cwiseInverse();
  // L M_l^{-1} L + alpha M_l: symmetric, and positive definite since L M_l^{-1} L >= 0 and M_l > 0.
  const Eigen::SparseMatrix<double> scaled_L = inverse_mass.asDiagonal() * L;
  Eigen::SparseMatrix<double> A = L * scaled_L;
  A += alpha * Ml;
  A.prune(0.0);
  const Eigen::MatrixX3d rhs = alpha * (Ml * p) - 2.0 * (L * mean_curvature_normals(normals, H));
  solver.compute(std::move(A));
  const Eigen::MatrixXd q = solver.solve(rhs);
  if (!q.allFinite()) throw NumericalError("regularization: the solver returned non-finite positions");
  return q;
}

RegularizationEnergy regularization_energy(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                           const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                           const Eigen::VectorXd& H, const Eigen::MatrixX3d& q) {
  check_inputs(L, M, p, normals, H);
  if (q.rows() != p.rows()) throw InputError("regularization energy: q and p have different vertex counts");
  const Eigen::VectorXd mass = lumped_mass(M).diagonal();
  const Eigen::MatrixX3d residual =
      mass.cwiseInverse().asDiagonal() * (L * q) + 2.0 * mean_curvature_normals(normals, H);
  const Eigen::MatrixX3d displacement = q - p;
  RegularizationEnergy e;
  e.laplacian = (mass.asDiagonal() * residual.cwiseAbs2()).sum();
  e.attachment = (mass.asDiagonal() * displacement.cwiseAbs2()).sum();
  return e;
}

}  // namespace corrlap

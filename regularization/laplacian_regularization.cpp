#include "laplacian_regularization.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/backends/iterative.hpp>
#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace corrlap {

namespace {

// The sizes and values of L, M and p, and of the normals and H where given (a curvature term given
// whole has neither).
void check_inputs(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, const Eigen::MatrixX3d& p,
                  const Eigen::MatrixX3d* normals, const Eigen::VectorXd* H) {
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
  if (normals && normals->rows() != n) size_error("normals", normals->rows(), normals->cols());
  if (H && H->size() != n) size_error("H", H->size(), 1);
  if (!p.allFinite()) throw InputError("regularization: a vertex position is not finite");
  if (!normals || !H) return;
  for (Eigen::Index v = 0; v < n; ++v) {
    if (!std::isfinite((*H)[v])) {
      std::ostringstream os;
      os << "regularization: the mean curvature of vertex " << v << " is " << (*H)[v];
      throw InputError(os.str());
    }
    if (!normals->row(v).allFinite() || std::abs(normals->row(v).norm() - 1.0) > 1e-6) {
      std::ostringstream os;
      os << "regularization: the normal of vertex " << v << " is not a unit vector (" << normals->row(v) << ")";
      throw InputError(os.str());
    }
  }
}

void check_inputs(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, const Eigen::MatrixX3d& p,
                  const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H) {
  check_inputs(L, M, p, &normals, &H);
}

// The rows H_v n_v^T.
Eigen::MatrixX3d mean_curvature_normals(const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H) {
  return H.asDiagonal() * normals;
}

// The part of the normal equations' right-hand side that alpha does not change, -2 L (H n) (#V x 3).
Eigen::MatrixX3d curvature_rhs(const Eigen::SparseMatrix<double>& L, const Eigen::MatrixX3d& normals,
                               const Eigen::VectorXd& H) {
  return -2.0 * (L * mean_curvature_normals(normals, H));
}

// curvature_rhs after the checks of check_inputs (the first thing a constructor delegating to the
// one with the curvature term given must do).
Eigen::MatrixX3d checked_curvature_rhs(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                       const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                       const Eigen::VectorXd& H) {
  check_inputs(L, M, p, normals, H);
  return curvature_rhs(L, normals, H);
}

// The right-hand side of the normal equations, alpha M_l p - 2 L (H n) (#V x 3), from its curvature part.
Eigen::MatrixX3d normal_equations_rhs(const Eigen::SparseMatrix<double>& Ml, const Eigen::MatrixX3d& p,
                                      const Eigen::MatrixX3d& curvature, double alpha) {
  return alpha * (Ml * p) + curvature;
}

// The relative residual of the normal equations, max over the columns of |R_j| / |b_j|.
double relative_residual(const Eigen::MatrixXd& R, const Eigen::MatrixXd& rhs) {
  double worst = 0.0;
  for (Eigen::Index j = 0; j < R.cols(); ++j)
    worst = std::max(worst, R.col(j).norm() / std::max(rhs.col(j).norm(), std::numeric_limits<double>::min()));
  return worst;
}

// area: the sum of M_l.
void check_alpha(double alpha, double area, const Eigen::MatrixX3d& p) {
  if (!(alpha > 0.0) || !std::isfinite(alpha))
    throw InputError("regularization: alpha must be a positive number", "alpha");
  const double largest = max_regularization_alpha(area, p.cwiseAbs().maxCoeff());
  if (alpha > largest) {
    std::ostringstream os;
    os << "regularization: alpha = " << alpha << " is beyond what the solve represents in double precision on "
       << "this surface (at most " << largest << "): the attachment term alpha M_l p would overflow";
    throw InputError(os.str(), "alpha");
  }
}

// A += diag(d), in place: a closed surface's L has every diagonal entry, so no insertion (a sparse
// sum with a diagonal matrix rebuilds the whole pattern, several times slower).
void add_to_diagonal(Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& d) {
  A.makeCompressed();
  for (Eigen::Index j = 0; j < A.outerSize(); ++j) {
    if (d[j] == 0.0) continue;
    bool found = false;
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it)
      if (it.index() == j) {
        it.valueRef() += d[j];
        found = true;
        break;
      }
    if (!found) A.coeffRef(j, j) += d[j];
  }
}

}  // namespace

double max_regularization_alpha(double area, double reach) {
  return kMaxAttachmentScale /
         (std::max(area, std::numeric_limits<double>::min()) * std::max(reach, std::numeric_limits<double>::min()));
}

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
  if (!(alpha0 >= 0.0) || !std::isfinite(alpha0))
    throw InputError("regularization: alpha0 must be a finite number >= 0 (0: no attachment)");
  return alpha0 / (h * h);
}

Eigen::MatrixX3d regularize_positions(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                      const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                      const Eigen::VectorXd& H, double alpha, LinearSolver& solver,
                                      SolverReport* report) {
  check_inputs(L, M, p, normals, H);
  const Eigen::SparseMatrix<double> Ml = lumped_mass(M);
  check_alpha(alpha, Ml.sum(), p);
  const Eigen::VectorXd inverse_mass = Ml.diagonal().cwiseInverse();
  // L M_l^{-1} L + alpha M_l: symmetric, and positive definite since L M_l^{-1} L >= 0 and M_l > 0.
  const Eigen::SparseMatrix<double> scaled_L = inverse_mass.asDiagonal() * L;
  Eigen::SparseMatrix<double> A = L * scaled_L;
  A += alpha * Ml;
  A.prune(0.0);
  const Eigen::MatrixX3d rhs = normal_equations_rhs(Ml, p, curvature_rhs(L, normals, H), alpha);
  solver.set_positions(p);  // orders the factorization (geometric nested dissection)
  solver.compute(std::move(A));
  const Eigen::MatrixXd q = solver.solve(rhs);
  if (!q.allFinite()) throw NumericalError("regularization: the solver returned non-finite positions");
  if (report) {
    report->status = SolverStatus::Success;
    // A was moved into the solver: A q from its factors L and M_l.
    const Eigen::MatrixXd Aq = L * (scaled_L * q) + alpha * (Ml * q);
    report->residual = relative_residual(rhs - Aq, rhs);
  }
  return q;
}

PreconditionedRegularization::PreconditionedRegularization(const Eigen::SparseMatrix<double>& L,
                                                           const Eigen::SparseMatrix<double>& M,
                                                           const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& normals,
                                                           const Eigen::VectorXd& H, LinearSolver& solver)
    : PreconditionedRegularization(L, M, p, checked_curvature_rhs(L, M, p, normals, H), solver) {}

PreconditionedRegularization::PreconditionedRegularization(const Eigen::SparseMatrix<double>& L,
                                                           const Eigen::SparseMatrix<double>& M,
                                                           const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& g,
                                                           LinearSolver& solver)
    : L_(L), p_(p), solver_(solver) {
  check_inputs(L, M, p, nullptr, nullptr);
  if (g.rows() != p.rows() || !g.allFinite())
    throw InputError("regularization: the curvature term must be finite, one row per vertex");
  lumped_mass_ = lumped_mass(M);
  mass_ = lumped_mass_.diagonal();
  inverse_mass_ = mass_.cwiseInverse();
  curvature_rhs_ = g;
}

Eigen::MatrixX3d PreconditionedRegularization::solve(double alpha, double accuracy, SolverReport* report,
                                                     double* error_bound, const Eigen::MatrixX3d* start) {
  if (!(accuracy >= 0.0) || !std::isfinite(accuracy))
    throw InputError("regularization: the solve accuracy must be a finite number >= 0", "accuracy");
  const Eigen::SparseMatrix<double>& L = L_;
  const Eigen::VectorXd &mass = mass_, &inverse_mass = inverse_mass_;
  check_alpha(alpha, mass.sum(), p_);
  if (start && (start->rows() != p_.rows() || !start->allFinite()))
    throw InputError("regularization: the start positions must be finite, one row per vertex", "start");
  const Eigen::MatrixX3d rhs = normal_equations_rhs(lumped_mass_, p_, curvature_rhs_, alpha);
  // B = sqrt(alpha) M_l - L, SPD when L is negative semi-definite (the header's bound).
  Eigen::SparseMatrix<double> B = L;  // a plain copy, negated in place: the expression -L is slower
  B *= -1.0;
  add_to_diagonal(B, std::sqrt(alpha) * mass);
  // The pattern is the same for every alpha (a positive diagonal, and -L's entries off it), so one
  // symbolic analysis serves every solve.
  B.prune(0.0);
  if (!analyzed_) {
    solver_.set_positions(p_);  // orders the factorization (geometric nested dissection)
    solver_.analyze(B);
    analyzed_ = true;
  }
  solver_.factorize_owned(std::move(B));
  LinearSolver& solver = solver_;
  Eigen::SparseMatrix<double> absL = L;  // a copy with its values replaced (faster than L.cwiseAbs())
  absL.makeCompressed();
  for (Eigen::Index i = 0; i < absL.nonZeros(); ++i) absL.valuePtr()[i] = std::abs(absL.valuePtr()[i]);
  PreconditionedSystem system;
  system.rows = p_.rows();
  system.total_rows = p_.rows();
  system.alpha = alpha;
  system.area = mass.sum();
  system.multiply = [&](const Eigen::MatrixXd& X) -> Eigen::MatrixXd {
    return L * (inverse_mass.asDiagonal() * (L * X)) + alpha * (mass.asDiagonal() * X);
  };
  // P^{-1} = B^{-1} M_l B^{-1}.
  system.precondition = [&](const Eigen::MatrixXd& R) -> Eigen::MatrixXd {
    return solver.solve(mass.asDiagonal() * solver.solve(R));
  };
  system.absolute_multiply = [&](const Eigen::MatrixXd& X) -> Eigen::MatrixXd {
    return absL * (inverse_mass.asDiagonal() * (absL * X)) + alpha * (mass.asDiagonal() * X);
  };
  const Eigen::MatrixXd rhs_columns = rhs;
  const Eigen::MatrixXd start_columns = start ? Eigen::MatrixXd(*start) : Eigen::MatrixXd();
  return solve_preconditioned(system, rhs_columns, start ? &start_columns : nullptr, accuracy, report, error_bound);
}

Eigen::MatrixXd solve_preconditioned(const PreconditionedSystem& system, const Eigen::MatrixXd& rhs,
                                     const Eigen::MatrixXd* start, double accuracy, SolverReport* report,
                                     double* error_bound) {
  const double alpha = system.alpha, area = system.area;
  const auto sum_over_parts = [&](Eigen::ArrayXd& sums) {
    if (system.sum_over_parts) system.sum_over_parts(sums);
  };
  const auto max_over_parts = [&](double x) { return system.max_over_parts ? system.max_over_parts(x) : x; };
  // Column-wise inner products over every part.
  const auto dots = [&](const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y) {
    Eigen::ArrayXd d = (X.array() * Y.array()).colwise().sum().transpose();
    sum_over_parts(d);
    return d;
  };
  SymmetricOperator A;
  A.rows = system.rows;
  // The CG blocks are transposed (k by n): multiply through plain n by k matrices.
  A.multiply_transposed = [&](const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt) {
    Yt = system.multiply(Xt.transpose()).transpose();
  };
  A.precondition_transposed = [&](const Eigen::MatrixXd& Rt, Eigen::MatrixXd& Zt) {
    Zt = system.precondition(Rt.transpose()).transpose();
  };
  A.sum_over_parts = system.sum_over_parts;
  // The header's bound on the RMS error of each coordinate, sqrt(2 r^T P^{-1} r / (alpha area)),
  // the worst column (one application of P^{-1}, the cost of a CG iteration).
  const auto bound_of = [&](const Eigen::MatrixXd& R) {
    const Eigen::ArrayXd rz = dots(R, system.precondition(R));
    return std::sqrt(2.0 * std::max(rz.maxCoeff(), 0.0) / (alpha * area));
  };
  // max over the columns of |R_j| / |b_j|.
  const Eigen::ArrayXd bb = dots(rhs, rhs);
  const auto relative = [&](const Eigen::MatrixXd& R) {
    const Eigen::ArrayXd rr = dots(R, R);
    double worst = 0.0;
    for (Eigen::Index j = 0; j < R.cols(); ++j)
      worst = std::max(worst, std::sqrt(rr[j]) / std::max(std::sqrt(bb[j]), std::numeric_limits<double>::min()));
    return worst;
  };
  // Corrected weights grow like 1/(u.n) where normals are nearly tangent to the surfels; A's
  // entries then span many orders of magnitude and CG's recurrence drifts from the true residual.
  // Each pass after the first solves for the true residual of the last (iterative refinement, at
  // most 3 passes), until the relative residual is 1e-10 or the componentwise backward error,
  // max_i |b - A q|_i / (|L| M_l^{-1} |L| |q| + alpha M_l |q| + |b|)_i, is below 1e-12 (the rounding
  // of A q is ~20 eps for rows of ~9 entries; one refinement pass reaches it, Skeel's result), or
  // until the error bound is below the accuracy asked.
  constexpr double kBackwardTolerance = 1e-12;
  const auto backward_error = [&](const Eigen::MatrixXd& q, const Eigen::MatrixXd& R) {
    const Eigen::MatrixXd scale = system.absolute_multiply(q.cwiseAbs()) + Eigen::MatrixXd(rhs.cwiseAbs());
    double worst = 0.0;
    for (Eigen::Index j = 0; j < q.cols(); ++j)
      for (Eigen::Index i = 0; i < q.rows(); ++i)
        if (scale(i, j) > 0.0) worst = std::max(worst, std::abs(R(i, j)) / scale(i, j));
    return max_over_parts(worst);
  };
  Config cg_options;
  cg_options.set("on_no_convergence", "warn");
  // 2 n of the whole system, the same on every part.
  cg_options.set("max_iterations", double(std::min<std::int64_t>(2 * system.total_rows, 1 << 30)));
  SolverReport local;
  SolverReport& cg = report ? *report : local;
  // Not from p: L p is the staircase's Laplacian, so |b - A p| is orders of magnitude above |b|.
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(system.rows, rhs.cols()), residual = rhs;
  if (start) {
    q = *start;
    residual = rhs - system.multiply(q);
  }
  int iterations = 0;
  double normwise = 1.0, backward = 1.0, bound = std::numeric_limits<double>::infinity();
  const auto at_rounding = [&] { return normwise <= 1e-10 || backward <= kBackwardTolerance; };  // NaN: not known
  const auto done = [&] { return at_rounding() || (accuracy > 0.0 && bound <= accuracy); };
  for (int pass = 0; pass < 3 && !done(); ++pass) {
    if (accuracy > 0.0) {
      // The bound is sqrt(2 r^T P^{-1} r / (alpha area)): CG stops on that norm of its recurrence
      // residual, at half the accuracy (room for the drift of the recurrence), checked below on the
      // true residual.
      cg_options.set("tolerance", 1e-10);
      cg_options.set("preconditioned_tolerance", 0.5 * accuracy * std::sqrt(0.5 * alpha * area));
    } else {
      // Each pass asks only for the reduction still missing: 1e-8 of b first (near the rounding
      // floor of a badly scaled L), then a tenth of what the nearer acceptance test still lacks (a
      // pass shrinks both errors by about its CG tolerance until the floor): fewer iterations than a
      // fixed tolerance (bench/RESULTS.md, "corrlap regularize: CHOLMOD thread policy, refinement
      // tolerances, face clusters").
      const double missing = pass == 0 ? 1e-8 : 0.1 * std::max(1e-10 / normwise, kBackwardTolerance / backward);
      cg_options.set("tolerance", std::clamp(missing, 1e-10, 0.1));
    }
    const Eigen::MatrixXd step = conjugate_gradient(A, residual, cg_options, &cg);
    iterations += cg.iterations;
    Eigen::ArrayXd non_finite(1);
    non_finite[0] = step.allFinite() ? 0.0 : 1.0;
    sum_over_parts(non_finite);
    if (non_finite[0] > 0.0) throw NumericalError("regularization: the solver returned non-finite positions");
    q += step;
    residual = rhs - system.multiply(q);
    normwise = relative(residual);
    if (accuracy > 0.0) bound = bound_of(residual);
    // The backward error only decides when the bound does not.
    backward =
        accuracy > 0.0 && bound <= accuracy ? std::numeric_limits<double>::quiet_NaN() : backward_error(q, residual);
  }
  cg.iterations = iterations;
  cg.residual = normwise;
  if (error_bound) *error_bound = accuracy > 0.0 ? bound : bound_of(residual);
  std::ostringstream os;
  os << "regularization: relative residual " << normwise << " after " << iterations
     << " preconditioned CG iterations, componentwise backward error " << backward;
  if (accuracy > 0.0) os << ", error bound " << bound << " (asked " << accuracy << ")";
  if (!done()) {
    cg.status = SolverStatus::NoConvergence;
    cg.message = os.str();
    throw SolverError(SolverStatus::NoConvergence, os.str());
  }
  cg.status = SolverStatus::Success;
  cg.message = accuracy == 0.0 && normwise > 1e-10 ? os.str() + " (the rounding of A q)" : std::string();
  return q;
}

Eigen::MatrixX3d regularize_positions_preconditioned(const Eigen::SparseMatrix<double>& L,
                                                     const Eigen::SparseMatrix<double>& M, const Eigen::MatrixX3d& p,
                                                     const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H,
                                                     double alpha, LinearSolver& solver, SolverReport* report,
                                                     double accuracy, double* error_bound) {
  PreconditionedRegularization regularization(L, M, p, normals, H, solver);
  return regularization.solve(alpha, accuracy, report, error_bound);
}

Eigen::MatrixX3d regularize_positions_unattached(const Eigen::SparseMatrix<double>& L,
                                                 const Eigen::SparseMatrix<double>& M, const Eigen::MatrixX3d& p,
                                                 const Eigen::MatrixX3d& normals, const Eigen::VectorXd& H,
                                                 LinearSolver& solver, SolverReport* report) {
  check_inputs(L, M, p, normals, H);
  const Eigen::VectorXd mass = lumped_mass(M).diagonal();
  const Eigen::Index n = p.rows();
  // Connected components of L's graph (its exact zeros are no edges): the null space of L.
  const Eigen::SparseMatrix<double>& S = L;
  std::vector<int> component(static_cast<std::size_t>(n), -1);
  int C = 0;
  std::vector<int> stack;
  for (Eigen::Index seed = 0; seed < n; ++seed) {
    if (component[std::size_t(seed)] >= 0) continue;
    component[std::size_t(seed)] = C;
    stack.assign(1, int(seed));
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (Eigen::SparseMatrix<double>::InnerIterator it(S, v); it; ++it)
        if (it.value() != 0.0 && component[std::size_t(it.index())] < 0) {
          component[std::size_t(it.index())] = C;
          stack.push_back(int(it.index()));
        }
    }
    ++C;
  }
  // g' = g - sum_c M_l 1_c (1_c^T g) / (1_c^T M_l 1_c), g = -2 M_l H n (§9.3).
  Eigen::MatrixX3d g = -2.0 * (mass.asDiagonal() * mean_curvature_normals(normals, H));
  Eigen::MatrixX3d g_sum = Eigen::MatrixX3d::Zero(C, 3), p_sum = Eigen::MatrixX3d::Zero(C, 3);
  Eigen::VectorXd mass_sum = Eigen::VectorXd::Zero(C);
  for (Eigen::Index v = 0; v < n; ++v) {
    const int c = component[std::size_t(v)];
    g_sum.row(c) += g.row(v);
    p_sum.row(c) += mass[v] * p.row(v);
    mass_sum[c] += mass[v];
  }
  for (Eigen::Index v = 0; v < n; ++v) {
    const int c = component[std::size_t(v)];
    g.row(v) -= mass[v] / mass_sum[c] * g_sum.row(c);
  }
  // The first vertex of each component is held at 0: -L without those rows and columns.
  std::vector<int> reduced(static_cast<std::size_t>(n), -1);
  std::vector<char> held(static_cast<std::size_t>(C), 0);
  int kept = 0;
  for (Eigen::Index v = 0; v < n; ++v) {
    const int c = component[std::size_t(v)];
    if (!held[std::size_t(c)]) {
      held[std::size_t(c)] = 1;
      continue;
    }
    reduced[std::size_t(v)] = kept++;
  }
  Eigen::MatrixX3d q = Eigen::MatrixX3d::Zero(n, 3);
  if (kept > 0) {
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(std::size_t(S.nonZeros()));
    for (Eigen::Index j = 0; j < n; ++j) {
      if (reduced[std::size_t(j)] < 0) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(S, j); it; ++it)
        if (reduced[std::size_t(it.index())] >= 0)
          entries.emplace_back(reduced[std::size_t(it.index())], reduced[std::size_t(j)], -it.value());
    }
    Eigen::SparseMatrix<double> K(kept, kept);
    K.setFromTriplets(entries.begin(), entries.end());
    Eigen::MatrixX3d rhs(kept, 3), positions(kept, 3);
    for (Eigen::Index v = 0; v < n; ++v)
      if (reduced[std::size_t(v)] >= 0) {
        rhs.row(reduced[std::size_t(v)]) = -g.row(v);
        positions.row(reduced[std::size_t(v)]) = p.row(v);
      }
    solver.set_positions(positions);
    try {
      solver.compute(std::move(K));
    } catch (const SolverError& e) {
      if (e.status() != SolverStatus::NotPositiveDefinite) throw;
      throw SolverError(SolverStatus::NotPositiveDefinite,
                        std::string("regularization without attachment (alpha0 = 0) needs L negative semi-definite "
                                    "with connected components: ") +
                            e.what() + "; use alpha0 > 0");
    }
    const Eigen::MatrixXd y = solver.solve(rhs);
    if (!y.allFinite()) throw NumericalError("regularization: the solver returned non-finite positions");
    for (Eigen::Index v = 0; v < n; ++v)
      if (reduced[std::size_t(v)] >= 0) q.row(v) = y.row(reduced[std::size_t(v)]);
  }
  // Each component at the input's M_l-weighted centroid.
  Eigen::MatrixX3d shift = p_sum;
  for (Eigen::Index v = 0; v < n; ++v) shift.row(component[std::size_t(v)]) -= mass[v] * q.row(v);
  for (Eigen::Index v = 0; v < n; ++v) {
    const int c = component[std::size_t(v)];
    q.row(v) += shift.row(c) / mass_sum[c];
  }
  if (report) {
    report->status = SolverStatus::Success;
    report->residual = relative_residual(L * q - g, g);
  }
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

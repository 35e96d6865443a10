#include "problems.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace corrlap {

using SpMat = Eigen::SparseMatrix<double>;

namespace {
/// -L restricted to the free unknowns (free_index[v] >= 0: v's index among them), built column by
/// column in place: a column of L is sorted by row and free_index keeps that order, so no triplet
/// list or transposed copy is needed (they were a large part of the peak memory of a large solve:
/// bench/RESULTS.md, "Scale on one machine").
SpMat negated_free_block(const SpMat& L, const std::vector<int>& free_index, Eigen::Index nfree) {
  SpMat A(nfree, nfree);
  std::vector<Eigen::Index> counts(std::size_t(nfree), 0);
  for (Eigen::Index j = 0; j < L.outerSize(); ++j) {
    if (free_index[std::size_t(j)] < 0) continue;
    for (SpMat::InnerIterator it(L, j); it; ++it)
      if (free_index[std::size_t(it.row())] >= 0) ++counts[std::size_t(free_index[std::size_t(j)])];
  }
  Eigen::Index total = 0;
  for (Eigen::Index c = 0; c < nfree; ++c) {
    A.outerIndexPtr()[c] = SpMat::StorageIndex(total);
    total += counts[std::size_t(c)];
  }
  A.outerIndexPtr()[nfree] = SpMat::StorageIndex(total);
  A.resizeNonZeros(total);
  for (Eigen::Index j = 0; j < L.outerSize(); ++j) {
    const int fj = free_index[std::size_t(j)];
    if (fj < 0) continue;
    Eigen::Index k = A.outerIndexPtr()[fj];
    for (SpMat::InnerIterator it(L, j); it; ++it) {
      const int fi = free_index[std::size_t(it.row())];
      if (fi < 0) continue;
      A.innerIndexPtr()[k] = fi;
      A.valuePtr()[k] = -it.value();
      ++k;
    }
  }
  return A;
}

/// The positions of the free unknowns, for the solver's ordering hint (LinearSolver::set_positions).
void hint_positions(LinearSolver& solver, const Eigen::MatrixX3d* positions, const std::vector<int>& free_index,
                    Eigen::Index nfree) {
  if (positions == nullptr || positions->rows() != Eigen::Index(free_index.size())) return;
  Eigen::MatrixX3d free_positions(nfree, 3);
  for (std::size_t v = 0; v < free_index.size(); ++v)
    if (free_index[v] >= 0) free_positions.row(free_index[v]) = positions->row(Eigen::Index(v));
  solver.set_positions(free_positions);
}
}  // namespace

Eigen::VectorXd solve_dirichlet(const SpMat& L, const SpMat& M, const Eigen::VectorXd& f, const std::vector<int>& fixed,
                                const Eigen::VectorXd& values, LinearSolver& solver,
                                const Eigen::MatrixX3d* positions) {
  const Eigen::Index n = L.rows();
  if (L.cols() != n || M.rows() != n || M.cols() != n || f.size() != n) {
    std::ostringstream os;
    os << "Dirichlet problem: sizes differ (L " << L.rows() << "x" << L.cols() << ", M " << M.rows() << "x" << M.cols()
       << ", f " << f.size() << ")";
    throw InputError(os.str());
  }
  if (Eigen::Index(fixed.size()) != values.size())
    throw InputError("Dirichlet problem: " + std::to_string(fixed.size()) + " fixed vertices but " +
                     std::to_string(values.size()) + " values");
  // L 1 = 0 (docs/math.md §0): without a fixed vertex -L is singular, and a Cholesky of a singular PSD
  // matrix may pass on rounding errors and return garbage, so refuse up front.
  if (fixed.empty()) throw InputError("Dirichlet problem: no fixed vertex (L 1 = 0 makes the system singular)");
  // Map every vertex to its index among the free ones (-1: fixed).
  std::vector<int> free_index(std::size_t(n), 0);
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    const int v = fixed[i];
    if (v < 0 || v >= n)
      throw InputError("Dirichlet problem: fixed vertex " + std::to_string(v) + " out of range [0, " +
                       std::to_string(n) + ")");
    if (free_index[std::size_t(v)] < 0)
      throw InputError("Dirichlet problem: vertex " + std::to_string(v) + " fixed twice");
    if (!std::isfinite(values[Eigen::Index(i)]))
      throw InputError("Dirichlet problem: value of vertex " + std::to_string(v) + " is not finite");
    free_index[std::size_t(v)] = -1;
  }
  int nfree = 0;
  for (auto& k : free_index)
    if (k >= 0) k = nfree++;
  if (nfree == 0) throw InputError("Dirichlet problem: every vertex is fixed");

  Eigen::VectorXd u_fixed = Eigen::VectorXd::Zero(n);
  for (std::size_t i = 0; i < fixed.size(); ++i) u_fixed[fixed[i]] = values[Eigen::Index(i)];

  // Free rows of L u = M f:  L_ff u_f = (M f)_f - L_fc u_c.  The solver gets -L_ff (SPD).
  const Eigen::VectorXd rhs_full = M * f - L * u_fixed;
  Eigen::VectorXd rhs(nfree);
  for (Eigen::Index v = 0; v < n; ++v)
    if (free_index[std::size_t(v)] >= 0) rhs[free_index[std::size_t(v)]] = -rhs_full[v];

  hint_positions(solver, positions, free_index, nfree);
  solver.compute(negated_free_block(L, free_index, nfree));
  const Eigen::VectorXd u_free = solver.solve(rhs);
  Eigen::VectorXd u = u_fixed;
  for (Eigen::Index v = 0; v < n; ++v)
    if (free_index[std::size_t(v)] >= 0) u[v] = u_free[free_index[std::size_t(v)]];
  return u;
}

SpMat pinned_system(const SpMat& L, int pin) {
  const Eigen::Index n = L.rows();
  if (L.cols() != n || pin < 0 || pin >= n)
    throw InputError("pinned system: pinned vertex " + std::to_string(pin) + " out of range for a " +
                     std::to_string(L.rows()) + " x " + std::to_string(L.cols()) + " matrix");
  std::vector<int> free_index(static_cast<std::size_t>(n));
  for (Eigen::Index v = 0; v < n; ++v) free_index[std::size_t(v)] = v == pin ? -1 : int(v < pin ? v : v - 1);
  return negated_free_block(L, free_index, n - 1);
}

double mass_weighted_mean(const SpMat& M, const Eigen::VectorXd& v) {
  if (M.rows() != v.size() || M.cols() != v.size())
    throw InputError("mass-weighted mean: M is " + std::to_string(M.rows()) + "x" + std::to_string(M.cols()) +
                     ", vector has " + std::to_string(v.size()) + " entries");
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(v.size());
  const Eigen::VectorXd m1 = M * ones;  // M symmetric: 1^T M v = (M 1)^T v
  return m1.dot(v) / m1.sum();
}

Eigen::VectorXd solve_neumann_poisson(const SpMat& L, const SpMat& M, const Eigen::VectorXd& b, LinearSolver& solver,
                                      double pin_value, int pin, const Eigen::MatrixX3d* positions) {
  // docs/math.md §10.4: without the compatibility projection, pinning makes a point source whose error
  // spoils the convergence rate.
  const Eigen::VectorXd compatible = b.array() - mass_weighted_mean(M, b);
  return solve_dirichlet(L, M, compatible, {pin}, Eigen::VectorXd::Constant(1, pin_value), solver, positions);
}

Eigen::MatrixXd solve_neumann_poisson_columns(const SpMat& L, const SpMat& M, const Eigen::MatrixXd& B,
                                              LinearSolver& solver, const Eigen::VectorXd& pin_values, int pin,
                                              const Eigen::MatrixX3d* positions) {
  const Eigen::Index n = L.rows();
  if (L.cols() != n || M.rows() != n || M.cols() != n || B.rows() != n || pin_values.size() != B.cols())
    throw InputError("Neumann problem: sizes differ (L " + std::to_string(L.rows()) + "x" + std::to_string(L.cols()) +
                     ", B " + std::to_string(B.rows()) + "x" + std::to_string(B.cols()) + ", " +
                     std::to_string(pin_values.size()) + " pin values)");
  if (pin < 0 || pin >= n) throw InputError("Neumann problem: pinned vertex " + std::to_string(pin) + " out of range");
  if (n < 2) throw InputError("Neumann problem: needs at least 2 vertices");
  // The same steps as solve_neumann_poisson (compatibility projection, pin, the free rows of
  // L g = M b_c with -L_ff handed to the solver), with every column sharing one factorization.
  const Eigen::VectorXd m1 = M * Eigen::VectorXd::Ones(n);
  const double area = m1.sum();
  Eigen::MatrixXd rhs_full(n, B.cols());
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    if (!std::isfinite(pin_values[j])) throw InputError("Neumann problem: pin value is not finite");
    const Eigen::VectorXd compatible = B.col(j).array() - m1.dot(B.col(j)) / area;
    Eigen::VectorXd u_fixed = Eigen::VectorXd::Zero(n);
    u_fixed[pin] = pin_values[j];
    rhs_full.col(j) = M * compatible - L * u_fixed;
  }
  const auto free_of = [pin](Eigen::Index v) { return v < pin ? v : v - 1; };  // v != pin
  std::vector<int> free_index(static_cast<std::size_t>(n));
  for (Eigen::Index v = 0; v < n; ++v) free_index[std::size_t(v)] = v == pin ? -1 : int(free_of(v));
  Eigen::MatrixXd rhs(n - 1, B.cols());
  for (Eigen::Index v = 0; v < n; ++v)
    if (v != pin) rhs.row(free_of(v)) = -rhs_full.row(v);
  hint_positions(solver, positions, free_index, n - 1);
  solver.compute(negated_free_block(L, free_index, n - 1));
  const Eigen::MatrixXd free_part = solver.solve(rhs);
  Eigen::MatrixXd G(n, B.cols());
  for (Eigen::Index v = 0; v < n; ++v)
    if (v != pin) G.row(v) = free_part.row(free_of(v));
  G.row(pin) = pin_values.transpose();
  return G;
}

ErrorNorms error_norms(const SpMat& M, const Eigen::VectorXd& e) {
  if (M.rows() != e.size() || M.cols() != e.size())
    throw InputError("error norms: M is " + std::to_string(M.rows()) + "x" + std::to_string(M.cols()) + ", error has " +
                     std::to_string(e.size()) + " entries");
  ErrorNorms r;
  r.linf = e.lpNorm<Eigen::Infinity>();
  const double area = (M * Eigen::VectorXd::Ones(e.size())).sum();
  r.l2 = std::sqrt(e.dot(M * e) / area);
  return r;
}

PoissonErrors poisson_errors(const SpMat& M, const Eigen::VectorXd& g, const Eigen::VectorXd& f) {
  if (g.size() != f.size()) throw InputError("Poisson errors: solution and reference sizes differ");
  const Eigen::VectorXd e = (g.array() - mass_weighted_mean(M, g)) - (f.array() - mass_weighted_mean(M, f));
  return error_norms(M, e);
}

double neumann_residual(const SpMat& L, const SpMat& M, const Eigen::VectorXd& b, const Eigen::VectorXd& g, int pin) {
  if (L.rows() != g.size() || L.cols() != g.size() || b.size() != g.size())
    throw InputError("Neumann residual: L is " + std::to_string(L.rows()) + "x" + std::to_string(L.cols()) +
                     ", b has " + std::to_string(b.size()) + " and g " + std::to_string(g.size()) + " entries");
  if (pin < 0 || pin >= g.size())
    throw InputError("Neumann residual: pinned vertex " + std::to_string(pin) + " out of range");
  const Eigen::VectorXd bc = b.array() - mass_weighted_mean(M, b);
  const Eigen::VectorXd Mb = M * bc;
  Eigen::VectorXd r = L * g - Mb;
  r[pin] = 0.0;
  return r.norm() / std::max(Mb.norm(), 1e-300);
}

namespace {
void check_vertex_operators(const Operators& ops, const Eigen::MatrixX3d& positions, const char* what) {
  if (ops.L.rows() != positions.rows() || ops.M.rows() != positions.rows())
    throw InputError(std::string(what) + ": operators are " + std::to_string(ops.L.rows()) + "x" +
                     std::to_string(ops.L.cols()) + " but there are " + std::to_string(positions.rows()) +
                     " positions" + (ops.domain == Operators::Domain::Faces ? " (the operators live on faces)" : ""));
}
}  // namespace

PoissonResult solve_poisson(const Operators& ops, const Eigen::MatrixX3d& positions, const TestFunction& function,
                            LinearSolver& solver, const Eigen::Vector3d& center) {
  check_vertex_operators(ops, positions, "Poisson problem");
  TestFunctionSamples s = sample_on_unit_sphere(function, positions, center);
  PoissonResult r;
  r.f = std::move(s.f);
  r.b = std::move(s.laplacian);
  r.g = solve_neumann_poisson(ops.L, ops.M, r.b, solver, r.f[0], 0, &positions);  // §10.4: g_0 = f(q_0)
  r.residual = neumann_residual(ops.L, ops.M, r.b, r.g, 0);
  r.errors = poisson_errors(ops.M, r.g, r.f);
  return r;
}

Eigen::VectorXd forward_laplacian(const SpMat& L, const SpMat& M, const Eigen::VectorXd& u, LinearSolver& solver,
                                  double dt, const Eigen::MatrixX3d* positions) {
  if (!(dt >= 0.0) || !std::isfinite(dt))
    throw InputError("forward evaluation: dt must be >= 0, got " + std::to_string(dt));
  if (L.rows() != u.size() || L.cols() != u.size() || M.rows() != u.size() || M.cols() != u.size())
    throw InputError("forward evaluation: L is " + std::to_string(L.rows()) + "x" + std::to_string(L.cols()) + ", M " +
                     std::to_string(M.rows()) + "x" + std::to_string(M.cols()) + ", u has " + std::to_string(u.size()) +
                     " entries");
  // docs/math.md §10.3: M - dt L is SPD for dt >= 0 because L is negative semi-definite.
  SpMat A = dt == 0.0 ? SpMat(M) : SpMat(M - dt * L);
  A.makeCompressed();
  if (positions != nullptr && positions->rows() == A.rows()) solver.set_positions(*positions);
  solver.compute(std::move(A));
  return solver.solve(L * u);
}

ErrorNorms forward_error(const Operators& ops, const Eigen::MatrixX3d& positions, const TestFunction& function,
                         LinearSolver& solver, double dt, const Eigen::Vector3d& center) {
  check_vertex_operators(ops, positions, "forward evaluation");
  const TestFunctionSamples s = sample_on_unit_sphere(function, positions, center);
  return error_norms(ops.M, forward_laplacian(ops.L, ops.M, s.f, solver, dt, &positions) - s.laplacian);
}

}  // namespace corrlap

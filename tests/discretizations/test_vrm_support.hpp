#pragma once
// Helpers shared by the VRM / heat-kernel / cotan tests: sphere1 surfaces, the backward Poisson
// protocol of docs/math.md §10.4, observed convergence orders.
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <functional>
#include <vector>

namespace corrlap::test {

inline SurfelMesh sphere1_surface(double h) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -2;
  p.max_aabb = 2;
  return extract_surface(digitize(make_implicit_shape("sphere1"), p));
}

/// One flat surfel: corners (0,0,0), (0,h,0), (0,h,h), (0,0,h), outward +x (docs/math.md §12.2).
inline SurfelMesh single_surfel(double h) {
  SurfelMesh m;
  m.positions.resize(4, 3);
  m.positions << 0, 0, 0, 0, h, 0, 0, h, h, 0, 0, h;
  m.faces.resize(1, 4);
  m.faces << 0, 1, 2, 3;
  m.h = h;
  return m;
}

/// Backward Poisson test of docs/math.md §10.4 with f = x^2 on the unit sphere (Delta f = 2 - 6 x^2),
/// at points q (unit vectors, one per unknown). Returns the M-weighted L2 error
/// sqrt(e^T M e / 1^T M 1) of g - mean(g) against f - mean(f). `iterative` uses CG (for the dense
/// rows of the heat kernel) instead of a sparse LDL^T.
inline double backward_poisson_error(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                     const Eigen::MatrixX3d& q, bool iterative = false) {
  const Eigen::Index n = L.rows();
  Eigen::VectorXd f(n), b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = q(i, 0);
    f[i] = x * x;
    b[i] = 2 - 6 * x * x;
  }
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  const Eigen::VectorXd M1 = M * ones;
  const double area = ones.dot(M1);
  b.array() -= M1.dot(b) / area;  // compatibility projection (docs/math.md §10.4)
  Eigen::VectorXd rhs = -(M * b);
  // pin g_0 = f_0: identity row/column 0, column moved to the right-hand side; -L is then SPD
  const double g0 = f[0];
  Eigen::SparseMatrix<double> A = -L;
  rhs += L.col(0) * g0;  // -(L g) = -M b  =>  -L_rest g_rest = -Mb + L_{.,0} g0
  rhs[0] = g0;
  A.prune([](Eigen::Index r, Eigen::Index c, double) { return r != 0 && c != 0; });
  A.coeffRef(0, 0) = 1.0;
  Eigen::VectorXd g;
  if (iterative) {
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg(A);
    cg.setTolerance(1e-12);
    cg.setMaxIterations(20000);
    g = cg.solve(rhs);
    if (cg.info() != Eigen::Success) throw NumericalError("CG did not converge");
  } else {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
    if (ldlt.info() != Eigen::Success) throw NumericalError("LDLT failed");
    g = ldlt.solve(rhs);
  }
  const Eigen::VectorXd e = (g.array() - M1.dot(g) / area).matrix() - (f.array() - M1.dot(f) / area).matrix();
  return std::sqrt(e.dot(M * e) / area);
}

inline Eigen::MatrixX3d radial(const Eigen::MatrixX3d& x) { return x.rowwise().normalized(); }

}  // namespace corrlap::test

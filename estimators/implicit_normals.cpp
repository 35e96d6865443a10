#include "implicit_normals.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

namespace corrlap {

namespace {
// The shape's gradient at x (world coordinates), from derivatives formed once per batch.
Eigen::Vector3d shape_gradient(const ImplicitShape& shape, const PolynomialGradient& grad, const Eigen::Vector3d& x) {
  return grad(shape.center.isZero() ? x : Eigen::Vector3d(x - shape.center));
}

Eigen::Vector3d project(const ImplicitShape& shape, const PolynomialGradient& grad, const Eigen::Vector3d& x,
                        const ProjectionParams& params) {
  // docs/math.md §1.5, the reference's ImplicitPolynomial3Shape::nearestPoint as documented there:
  // x_n = x_{n-1} - gamma * P(x_{n-1}) * grad P / |grad P|^2, stopped after max_iterations steps
  // or as soon as |P(x_n)| < accuracy (a criterion on the value of P, not on the step length).
  Eigen::Vector3d p = x;
  for (int it = 0; it < params.max_iterations; ++it) {
    const double value = shape.value(p);
    if (std::abs(value) < params.accuracy) break;
    const Eigen::Vector3d g = shape_gradient(shape, grad, p);
    const double g2 = g.squaredNorm();
    if (g2 == 0.0 || !std::isfinite(g2)) break;
    p -= (params.gamma * value / g2) * g;
  }
  return p;
}

Eigen::Vector3d normal_at(const ImplicitShape& shape, const PolynomialGradient& grad, const Eigen::Vector3d& x,
                          const ProjectionParams& params) {
  if (shape.sphere_radius() > 0.0) {
    const Eigen::Vector3d d = x - shape.center;
    const double n = d.norm();
    return n > 0 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::Zero();
  }
  const Eigen::Vector3d g = shape_gradient(shape, grad, project(shape, grad, x, params));
  const double n = g.norm();
  return n > 0 ? Eigen::Vector3d(g / n) : Eigen::Vector3d::Zero();
}
}  // namespace

Eigen::Vector3d project_onto_surface(const ImplicitShape& shape, const Eigen::Vector3d& x,
                                     const ProjectionParams& params) {
  return project(shape, PolynomialGradient(shape.polynomial), x, params);
}

Eigen::Vector3d true_normal(const ImplicitShape& shape, const Eigen::Vector3d& x, const ProjectionParams& params) {
  return normal_at(shape, PolynomialGradient(shape.polynomial), x, params);
}

Eigen::MatrixX3d true_face_normals(const ImplicitShape& shape, const SurfelMesh& mesh, const ProjectionParams& params) {
  const Eigen::MatrixX3d c = mesh.face_centroids();
  Eigen::MatrixX3d n(c.rows(), 3);
  const PolynomialGradient grad(shape.polynomial);
  tbb::parallel_for(Eigen::Index(0), c.rows(), [&](Eigen::Index f) {
    n.row(f) = normal_at(shape, grad, c.row(f).transpose(), params).transpose();
  });
  return n;
}

Eigen::MatrixX3d true_vertex_normals(const ImplicitShape& shape, const SurfelMesh& mesh,
                                     const ProjectionParams& params) {
  Eigen::MatrixX3d n(mesh.positions.rows(), 3);
  const PolynomialGradient grad(shape.polynomial);
  tbb::parallel_for(Eigen::Index(0), mesh.positions.rows(), [&](Eigen::Index v) {
    n.row(v) = normal_at(shape, grad, mesh.positions.row(v).transpose(), params).transpose();
  });
  return n;
}

namespace {
ProjectionParams precise_projection() {
  ProjectionParams p;
  p.max_iterations = 200;
  p.accuracy = 1e-12;
  return p;
}
}  // namespace

Eigen::VectorXd distances_to_surface(const ImplicitShape& shape, const Eigen::MatrixX3d& points) {
  Eigen::VectorXd d(points.rows());
  const double r = shape.sphere_radius();
  const ProjectionParams params = precise_projection();
  const PolynomialGradient grad(shape.polynomial);
  tbb::parallel_for(Eigen::Index(0), points.rows(), [&](Eigen::Index i) {
    const Eigen::Vector3d x = points.row(i).transpose();
    d[i] = r > 0.0 ? std::abs((x - shape.center).norm() - r) : (x - project(shape, grad, x, params)).norm();
  });
  return d;
}

Eigen::VectorXd true_mean_curvatures(const ImplicitShape& shape, const Eigen::MatrixX3d& points) {
  const PolynomialGradient grad(shape.polynomial);
  const PolynomialGradient second[3] = {PolynomialGradient(grad.derivative(0)), PolynomialGradient(grad.derivative(1)),
                                        PolynomialGradient(grad.derivative(2))};
  const ProjectionParams params = precise_projection();
  Eigen::VectorXd H(points.rows());
  tbb::parallel_for(Eigen::Index(0), points.rows(), [&](Eigen::Index i) {
    const Eigen::Vector3d q = project(shape, grad, points.row(i).transpose(), params) - shape.center;
    const Eigen::Vector3d g = grad(q);
    Eigen::Matrix3d hessian;
    for (int a = 0; a < 3; ++a) hessian.row(a) = second[a](q).transpose();
    const double g2 = g.squaredNorm();
    H[i] = (g2 * hessian.trace() - g.dot(hessian * g)) / (2.0 * g2 * std::sqrt(g2));
  });
  return H;
}

}  // namespace corrlap

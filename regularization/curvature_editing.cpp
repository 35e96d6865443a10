#include "curvature_editing.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <sstream>

namespace corrlap {

PrincipalCurvatureEdit PrincipalCurvatureEdit::parse(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return InputError("principal curvature edit '" + text + "': " + why +
                      " (expected scale:S, set:V or clamp:V, e.g. scale:2)");
  };
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos) throw bad("no ':'");
  const std::string kind = text.substr(0, colon), number = text.substr(colon + 1);
  PrincipalCurvatureEdit e;
  if (kind == "scale")
    e.kind = Kind::Scale;
  else if (kind == "set")
    e.kind = Kind::Set;
  else if (kind == "clamp")
    e.kind = Kind::Clamp;
  else
    throw bad("unknown edit '" + kind + "'");
  std::size_t used = 0;
  try {
    e.value = std::stod(number, &used);
  } catch (const std::exception&) {
    throw bad("'" + number + "' is not a number");
  }
  if (used != number.size() || !std::isfinite(e.value)) throw bad("'" + number + "' is not a finite number");
  if (e.kind == Kind::Clamp && e.value < 0) throw bad("the clamp bound must be >= 0");
  return e;
}

double PrincipalCurvatureEdit::apply(double k) const {
  switch (kind) {
    case Kind::None:
      return k;
    case Kind::Scale:
      return value * k;
    case Kind::Set:
      return value;
    case Kind::Clamp:
      return std::clamp(k, -value, value);
  }
  return k;
}

std::string PrincipalCurvatureEdit::describe() const {
  std::ostringstream os;
  switch (kind) {
    case Kind::None:
      return "none";
    case Kind::Scale:
      os << "scale:";
      break;
    case Kind::Set:
      os << "set:";
      break;
    case Kind::Clamp:
      os << "clamp:";
      break;
  }
  os << value;
  return os.str();
}

std::vector<Eigen::Matrix3d> edited_shape_operators(const Eigen::VectorXd& k1, const Eigen::VectorXd& k2,
                                                    const Eigen::MatrixX3d& d1, const Eigen::MatrixX3d& d2,
                                                    const PrincipalCurvatureEdit& edit1,
                                                    const PrincipalCurvatureEdit& edit2) {
  const Eigen::Index n = k1.size();
  if (k2.size() != n || d1.rows() != n || d2.rows() != n)
    throw InputError("edited_shape_operators: principal curvatures and directions of different sizes");
  std::vector<Eigen::Matrix3d> S(static_cast<std::size_t>(n));
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Vector3d a = d1.row(v).transpose(), b = d2.row(v).transpose();
    const double k1e = edit1.apply(k1[v]), k2e = edit2.apply(k2[v]);
    if (!std::isfinite(k1e) || !std::isfinite(k2e) || !a.allFinite() || !b.allFinite())
      throw NumericalError("edited_shape_operators: the principal curvatures of vertex " + std::to_string(v) +
                           " are not finite");
    S[std::size_t(v)] = k1e * a * a.transpose() + k2e * b * b.transpose();
  }
  return S;
}

Eigen::MatrixX3d integrate_shape_operator(const SurfelMesh& mesh, const std::vector<Eigen::Matrix3d>& S,
                                          const Eigen::MatrixX3d& normals, double size, double attachment,
                                          LinearSolver& solver) {
  const int V = mesh.num_vertices();
  if (int(S.size()) != V || normals.rows() != V)
    throw InputError("integrate_shape_operator: " + std::to_string(S.size()) + " shape operators and " +
                     std::to_string(normals.rows()) + " normals for " + std::to_string(V) + " vertices");
  if (!(attachment > 0.0) || !std::isfinite(attachment))
    throw InputError("integrate_shape_operator: the normal attachment must be positive");
  if (!(size > 0.0) || !std::isfinite(size)) throw InputError("integrate_shape_operator: the size must be positive");
  const double h = mesh.grid_step();
  const double lambda = attachment / (size * size) * h * h;
  const EdgeTopology topology = build_edges(mesh);
  // Normal equations of the edge least squares: (G^T G + lambda I) n' = G^T d + lambda n, G the
  // edge-vertex incidence (row e: -1 at a, +1 at b), d_e = (S'_a + S'_b)/2 (p_b - p_a).
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(std::size_t(4 * topology.num_edges() + V));
  Eigen::MatrixXd rhs = lambda * normals;
  for (int e = 0; e < topology.num_edges(); ++e) {
    const int a = topology.edges(e, 0), b = topology.edges(e, 1);
    const Eigen::Vector3d d =
        0.5 * (S[std::size_t(a)] + S[std::size_t(b)]) * (mesh.positions.row(b) - mesh.positions.row(a)).transpose();
    entries.emplace_back(a, a, 1.0);
    entries.emplace_back(b, b, 1.0);
    entries.emplace_back(a, b, -1.0);
    entries.emplace_back(b, a, -1.0);
    rhs.row(b) += d.transpose();
    rhs.row(a) -= d.transpose();
  }
  for (int v = 0; v < V; ++v) entries.emplace_back(v, v, lambda);
  Eigen::SparseMatrix<double> A(V, V);
  A.setFromTriplets(entries.begin(), entries.end());
  solver.compute(A);
  Eigen::MatrixX3d n = solver.solve(rhs);
  for (int v = 0; v < V; ++v) {
    const double norm = n.row(v).norm();
    if (!(norm > 1e-12) || !std::isfinite(norm))
      throw NumericalError("integrate_shape_operator: the integrated normal of vertex " + std::to_string(v) +
                           " vanishes (edits inconsistent with any surface? raise the attachment)");
    n.row(v) /= norm;
  }
  return n;
}

}  // namespace corrlap

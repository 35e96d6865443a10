#include "alignment_regularization.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/regularization/solution_check.hpp>
#include <limits>
#include <vector>

namespace corrlap {

namespace {

// Edge neighbours of every pointel (CSR), for the fairness term's b_i.
struct PointelNeighbours {
  std::vector<int> start, ids;
};
PointelNeighbours pointel_neighbours(const SurfelMesh& mesh, const EdgeTopology& topology) {
  const int V = mesh.num_vertices();
  PointelNeighbours n;
  std::vector<int> count(std::size_t(V), 0);
  for (int e = 0; e < topology.num_edges(); ++e) {
    ++count[std::size_t(topology.edges(e, 0))];
    ++count[std::size_t(topology.edges(e, 1))];
  }
  n.start.assign(std::size_t(V) + 1, 0);
  for (int v = 0; v < V; ++v) n.start[std::size_t(v) + 1] = n.start[std::size_t(v)] + count[std::size_t(v)];
  n.ids.resize(std::size_t(n.start.back()));
  std::vector<int> fill(n.start.begin(), n.start.end() - 1);
  for (int e = 0; e < topology.num_edges(); ++e) {
    const int a = topology.edges(e, 0), b = topology.edges(e, 1);
    n.ids[std::size_t(fill[std::size_t(a)]++)] = b;
    n.ids[std::size_t(fill[std::size_t(b)]++)] = a;
  }
  return n;
}

struct Problem {
  const SurfelMesh& mesh;
  const Eigen::MatrixX3d& normals;
  const Eigen::MatrixX3d& p;  // input, grid units
  const AlignmentParams& params;
  PointelNeighbours neighbours;
  std::vector<int> surfels_per_pointel;
};

// docs/math.md §9.1: E at q, and the reference's descent direction g (when g is given).
double energy_and_gradient(const Problem& pr, const Eigen::MatrixX3d& q, Eigen::MatrixX3d* g) {
  const AlignmentParams& a = pr.params;
  const Eigen::MatrixX3d data = pr.p - q;
  double energy = a.alpha * data.squaredNorm();
  if (g) *g = 2.0 * a.alpha * data;  // the reference's sign: the exact gradient is the opposite
  Eigen::MatrixX3d align = Eigen::MatrixX3d::Zero(q.rows(), 3);
  for (int f = 0; f < pr.mesh.num_faces(); ++f) {
    const Eigen::RowVector3d n = pr.normals.row(f);
    for (int j = 0; j < 4; ++j) {
      const int c0 = pr.mesh.faces(f, j), c1 = pr.mesh.faces(f, (j + 1) % 4);
      const double c = (q.row(c0) - q.row(c1)).dot(n);
      energy += a.beta * c * c;
      align.row(c0) += c * n;  // the first endpoint only
    }
  }
  if (g)
    for (Eigen::Index v = 0; v < q.rows(); ++v)
      g->row(v) += 2.0 * a.beta * align.row(v) / double(pr.surfels_per_pointel[std::size_t(v)]);
  for (Eigen::Index v = 0; v < q.rows(); ++v) {
    const int begin = pr.neighbours.start[std::size_t(v)], end = pr.neighbours.start[std::size_t(v) + 1];
    Eigen::RowVector3d b = Eigen::RowVector3d::Zero();
    for (int k = begin; k < end; ++k) b += q.row(pr.neighbours.ids[std::size_t(k)]);
    const Eigen::RowVector3d d = q.row(v) - b / double(end - begin);
    energy += a.gamma * d.squaredNorm();
    if (g) g->row(v) += 2.0 * a.gamma * d;  // the neighbours held fixed
  }
  return energy;
}

Problem make_problem(const SurfelMesh& mesh, const Eigen::MatrixX3d& normals, const Eigen::MatrixX3d& p,
                     const AlignmentParams& params) {
  check_normals(normals, mesh.num_faces(), "alignment regularization: face normals");
  const auto check = [](double value, const char* name, bool zero_allowed) {
    if (std::isfinite(value) && (value > 0.0 || (zero_allowed && value == 0.0))) return;
    throw InputError(std::string("alignment regularization: ") + name + " must be a finite number " +
                         (zero_allowed ? ">= 0" : "> 0") + ", got " + std::to_string(value),
                     name);
  };
  check(params.alpha, "alpha", false);
  check(params.beta, "beta", true);
  check(params.gamma, "gamma", true);
  check(params.dt, "dt", false);
  check(params.epsilon, "epsilon", false);
  const EdgeTopology topology = build_edges(mesh);
  if (!compute_mesh_info(mesh, topology).closed())
    throw InputError("alignment regularization: the surface is open (it has boundary edges)");
  Problem pr{mesh, normals, p, params, pointel_neighbours(mesh, topology), {}};
  pr.surfels_per_pointel.assign(std::size_t(mesh.num_vertices()), 0);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int j = 0; j < 4; ++j) ++pr.surfels_per_pointel[std::size_t(mesh.faces(f, j))];
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (pr.surfels_per_pointel[std::size_t(v)] == 0)
      throw InputError("alignment regularization: vertex " + std::to_string(v) + " belongs to no face");
  return pr;
}

}  // namespace

double alignment_energy(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Eigen::MatrixX3d& p,
                        const Eigen::MatrixX3d& q, const AlignmentParams& params) {
  const Problem pr = make_problem(mesh, face_normals, p, params);
  return energy_and_gradient(pr, q, nullptr);
}

AlignmentResult alignment_regularization(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals,
                                         const AlignmentParams& params) {
  const double h = mesh.grid_step();
  const Eigen::MatrixX3d p = mesh.positions / h;  // the reference works in grid units
  const Problem pr = make_problem(mesh, face_normals, p, params);
  Eigen::MatrixX3d q = p, g;
  AlignmentResult r;
  r.energy_initial = energy_and_gradient(pr, q, nullptr);
  double step = params.dt, energy = r.energy_initial, last = 0.0;
  for (int it = 0; it < params.max_iterations; ++it) {
    energy = energy_and_gradient(pr, q, &g);
    if (it > 0) step *= energy > last ? 0.5 : 1.1;
    if (step < params.epsilon) break;
    last = energy;
    q -= step * g;
    if (params.clamp) q = q.array().max(p.array() - 0.5).min(p.array() + 0.5).matrix();
    r.iterations = it + 1;
  }
  r.energy_final = energy;
  r.positions = q * h;
  (void)check_solution(mesh, r.positions, std::nullopt, "alignment regularization");
  return r;
}

AlignmentResult alignment_minimizer(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, LinearSolver& solver,
                                    const AlignmentParams& params) {
  const double h = mesh.grid_step();
  const Eigen::MatrixX3d p = mesh.positions / h;  // grid units, as the energy
  const Problem pr = make_problem(mesh, face_normals, p, params);
  const int V = mesh.num_vertices();
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(std::size_t(V) * 3 + std::size_t(mesh.num_faces()) * 4 * 36);
  for (int i = 0; i < 3 * V; ++i) t.emplace_back(i, i, params.alpha);
  // Alignment: beta ((q_a - q_b) . n)^2 for the edge (a, b) of a surfel of normal n.
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d n = face_normals.row(f).transpose();
    const Eigen::Matrix3d nn = params.beta * n * n.transpose();
    for (int j = 0; j < 4; ++j) {
      const int a = mesh.faces(f, j), b = mesh.faces(f, (j + 1) % 4);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          t.emplace_back(3 * a + r, 3 * a + c, nn(r, c));
          t.emplace_back(3 * b + r, 3 * b + c, nn(r, c));
          t.emplace_back(3 * a + r, 3 * b + c, -nn(r, c));
          t.emplace_back(3 * b + r, 3 * a + c, -nn(r, c));
        }
    }
  }
  // Fairness: gamma |(I - W) q|^2 per coordinate.
  std::vector<Eigen::Triplet<double>> w;
  for (int v = 0; v < V; ++v) {
    const int begin = pr.neighbours.start[std::size_t(v)], end = pr.neighbours.start[std::size_t(v) + 1];
    w.emplace_back(v, v, 1.0);
    for (int k = begin; k < end; ++k) w.emplace_back(v, pr.neighbours.ids[std::size_t(k)], -1.0 / double(end - begin));
  }
  Eigen::SparseMatrix<double> IW(V, V);
  IW.setFromTriplets(w.begin(), w.end());
  const Eigen::SparseMatrix<double> G = Eigen::SparseMatrix<double>(IW.transpose()) * IW;
  for (int j = 0; j < G.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(G, j); it; ++it)
      for (int k = 0; k < 3; ++k)
        t.emplace_back(3 * int(it.row()) + k, 3 * int(it.col()) + k, params.gamma * it.value());
  Eigen::SparseMatrix<double> H(3 * V, 3 * V);
  H.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd rhs(3 * V);
  for (int v = 0; v < V; ++v)
    for (int k = 0; k < 3; ++k) rhs[3 * v + k] = params.alpha * p(v, k);
  AlignmentResult r;
  r.energy_initial = energy_and_gradient(pr, p, nullptr);
  solver.compute(H);  // kept for the residual
  const Eigen::VectorXd x = solver.solve(rhs);
  if (!x.allFinite()) throw NumericalError("alignment minimizer: the solver returned non-finite positions");
  Eigen::MatrixX3d q(V, 3);
  for (int v = 0; v < V; ++v) q.row(v) = x.segment<3>(3 * v).transpose();
  r.energy_final = energy_and_gradient(pr, q, nullptr);
  r.positions = q * h;
  const double residual = (rhs - H * x).norm() / std::max(rhs.norm(), std::numeric_limits<double>::min());
  (void)check_solution(mesh, r.positions, residual, "alignment minimizer");
  return r;
}

}  // namespace corrlap

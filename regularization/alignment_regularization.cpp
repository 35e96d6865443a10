#include "alignment_regularization.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/normal_fields.hpp>
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
  const EdgeTopology topology = build_edges(mesh);
  for (const int n : topology.faces_per_edge)
    if (n == 1) throw InputError("alignment regularization: the surface is open (it has boundary edges)");
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
  return r;
}

}  // namespace corrlap

#include "convolved_trivial_normals.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <queue>
#include <vector>

namespace corrlap {

Eigen::MatrixX3d convolved_trivial_normals(const SurfelMesh& mesh, double t) {
  if (!(t > 0.0) || !std::isfinite(t)) throw InputError("convolved trivial normals: t-ring must be positive");
  const int F = mesh.num_faces();
  const double h = mesh.grid_step();
  const Eigen::MatrixX3d trivial = mesh.face_normals_from_positions();
  const Eigen::MatrixX3d centroid = mesh.face_centroids() / h;  // grid units
  // Faces across each edge (all of them on a non-manifold edge), CSR by face.
  const EdgeTopology topology = build_edges(mesh);
  std::vector<std::vector<int>> edge_faces(static_cast<std::size_t>(topology.num_edges()));
  for (int f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i) edge_faces[std::size_t(topology.face_edges(f, i))].push_back(f);
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(F));
  for (int f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i)
      for (int g : edge_faces[std::size_t(topology.face_edges(f, i))])
        if (g != f) neighbours[std::size_t(f)].push_back(g);

  struct Scratch {
    std::vector<int> seen;  // stamp: the face whose walk last saw it
  };
  tbb::enumerable_thread_specific<Scratch> scratch([F] { return Scratch{std::vector<int>(std::size_t(F), -1)}; });
  Eigen::MatrixX3d result(F, 3);
  tbb::parallel_for(0, F, [&](int f) {
    std::vector<int>& seen = scratch.local().seen;
    // Faces in increasing distance from f, as the reference's distance-ordered breadth-first walk.
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    queue.push({0.0, f});
    seen[std::size_t(f)] = f;
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    while (!queue.empty()) {
      const auto [d, g] = queue.top();
      queue.pop();
      if (d >= t) break;
      sum += (1.0 - (t - d) / (t * t)) * trivial.row(g);
      for (int k : neighbours[std::size_t(g)])
        if (seen[std::size_t(k)] != f) {
          seen[std::size_t(k)] = f;
          queue.push({(centroid.row(k) - centroid.row(f)).norm(), k});
        }
    }
    const double norm = sum.norm();
    result.row(f) = norm > 0.0 ? Eigen::RowVector3d(sum / norm) : trivial.row(f);
  });
  return result;
}

}  // namespace corrlap

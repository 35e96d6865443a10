#pragma once
// Edges of a quad mesh with the reference's numbering and sign convention (docs/math.md §0), and
// topological summaries (Euler characteristic, components, boundary, non-manifold elements).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "surfel_mesh.hpp"

namespace corrlap {

/// Undirected edges {a, b} stored once as (min, max), numbered by lexicographic rank (docs/math.md §0).
struct EdgeTopology {
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> edges;       ///< #E x 2, (min, max)
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> face_edges;  ///< edge id of local edge i (corner i -> i+1)
  Eigen::Matrix<std::int8_t, Eigen::Dynamic, 4, Eigen::RowMajor> face_edge_signs;  ///< s_{f,i} = +1 if v_i < v_{i+1}
  std::vector<int> faces_per_edge;  ///< number of incident faces (1 boundary, 2 manifold, >2 non-manifold)

  int num_edges() const { return int(edges.rows()); }
};

/// Builds the edge numbering of docs/math.md §0 for the quads of `mesh`.
EdgeTopology build_edges(const SurfelMesh& mesh);

/// Counts reported by `corrlap info`.
struct MeshInfo {
  int vertices = 0, edges = 0, faces = 0;
  int euler = 0;                 ///< V - E + F
  int components = 0;            ///< connected components (faces joined by shared vertices)
  int boundary_edges = 0;        ///< edges with exactly one face
  int nonmanifold_edges = 0;     ///< edges with more than two faces
  int nonmanifold_vertices = 0;  ///< vertices whose incident faces form more than one fan
  int isolated_vertices = 0;     ///< vertices used by no face
  double area = 0.0;             ///< digital (uncorrected) area: sum of quad areas
  Eigen::Vector3d bbox_min = Eigen::Vector3d::Zero(), bbox_max = Eigen::Vector3d::Zero();
  /// Genus from chi = 2C - 2g when the surface is closed and manifold, else -1.
  int genus() const;
  bool closed() const { return boundary_edges == 0; }
  bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0; }
};

MeshInfo compute_mesh_info(const SurfelMesh& mesh, const EdgeTopology& topology);
inline MeshInfo compute_mesh_info(const SurfelMesh& mesh) { return compute_mesh_info(mesh, build_edges(mesh)); }

/// Component id (0..C-1) of every face.
std::vector<int> face_components(const SurfelMesh& mesh, int& num_components);

}  // namespace corrlap

#pragma once
// Corrected curvature measures (docs/math.md §8; the reference's CorrectedNormalCurrentComputer/Formula):
// per-face measures mu0, mu1, mu2, muXY for interpolated vertex normals (fan around the
// barycentre), or constant face normals (mu0 on faces, mu1 on edges); ball measures with the
// reference's ball-face inclusion ratio and a breadth-first walk from a seed face; H, G, principal
// curvatures and directions.
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <vector>

namespace corrlap {

/// Curvature estimates at a set of points (faces or vertices).
struct CurvatureEstimates {
  Eigen::VectorXd H, G, k1, k2;  ///< mean, Gaussian, principal curvatures (k1 <= k2, docs/math.md §8.3)
  Eigen::MatrixX3d d1, d2;       ///< unit principal directions of k1 and k2
  Eigen::VectorXd area;          ///< mu0 of the ball
};

class CorrectedCurvature {
 public:
  /// Interpolated normals (docs/math.md §8.1/8.2): vertex_normals #V x 3 (unit, checked).
  static CorrectedCurvature interpolated(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals);
  /// Constant per-face normals (reference fallback): mu0 per face, mu1 and muXY per edge
  /// (dihedral angle), mu2 per vertex (spherical polygon of the surrounding face normals).
  static CorrectedCurvature constant(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals);

  bool interpolated_normals() const { return interpolated_; }
  const Eigen::VectorXd& face_mu0() const { return mu0_; }
  const Eigen::VectorXd& face_mu1() const { return mu1_; }  ///< zero in the constant variant
  const Eigen::VectorXd& face_mu2() const { return mu2_; }
  const std::vector<Eigen::Matrix3d>& face_muXY() const { return muxy_; }
  const Eigen::VectorXd& edge_mu1() const { return edge_mu1_; }                 ///< constant variant only
  const Eigen::VectorXd& vertex_mu2() const { return vertex_mu2_; }             ///< constant variant only
  const std::vector<Eigen::Matrix3d>& edge_muXY() const { return edge_muxy_; }  ///< constant variant only
  /// Totals over the whole mesh (mu0, mu1, mu2).
  Eigen::Vector3d totals() const;

  /// Faces meeting the ball B(x, r) with their inclusion ratios (docs/math.md §8.3), walk from seed face.
  std::vector<std::pair<int, double>> faces_in_ball(const Eigen::Vector3d& x, double r, int seed) const;

  /// Estimates with balls of radius r centred at face centroids (seed = the face; N = face normal).
  CurvatureEstimates at_faces(double r) const;
  /// Estimates with balls centred at vertices (seed = an incident face; N = vertex normal, or the
  /// normalized sum of incident face normals in the constant variant).
  CurvatureEstimates at_vertices(double r) const;
  /// Mean curvature and ball area alone.
  struct MeanCurvature {
    Eigen::VectorXd H, area;  ///< #V each
  };
  /// Equals at_vertices(r).H and .area (the same faces and weights; sums to rounding), faster for
  /// what regularization needs: no muXY sums nor eigen solves, and the walk classifies a face from
  /// its centroid's distance d alone when it can (whole if d + rho <= r, out if d - rho >= r, rho
  /// the largest corner distance from the centroid), reading its corners only near the sphere;
  /// for radii of 12 edges and more, edge-connected clusters of faces within a cube of side 4
  /// edges are summed at once when the ball holds all their corners (then only the faces around
  /// them are walked on).
  /// The constant variant and radii below 1e-6 use at_vertices.
  MeanCurvature mean_curvature_at_vertices(double r) const;
  /// Approximates mean_curvature_at_vertices(r) with the ball walked at fewer vertices, the
  /// sites: chosen per cell of a lattice of side 2 spacing anchored at the origin, greedily in
  /// Z-order among the cell's vertices, so that every vertex has a site of its cell within
  /// spacing / 2 whose normal is within 60 degrees of its own (sheets of a thin part get their own
  /// sites). Any part of the mesh holding a cell's vertices chooses that cell's sites alike. A
  /// vertex's H (and area) is the mean over those sites within `spacing`, weighted by
  /// (1 - (d / spacing)^2)^2. The ball estimate varies at the scale of r, not of an edge, so a
  /// spacing of a fraction of r changes it far less than its own error (docs/math.md §8.4); the
  /// walk's cost per vertex grows as r^2, the sites' count falls as 1 / spacing^2. Spacings below
  /// 2 edges (less 1e-9 of them) walk every vertex (then the result is
  /// mean_curvature_at_vertices(r)).
  MeanCurvature mean_curvature_at_sites(double r, double spacing) const;
  /// mean_curvature_at_sites(r, spacing) at the listed vertices (the others get 0), walking only
  /// the sites within `spacing` of them. A listed vertex's value depends on the mesh within
  /// 3 spacing + r of it alone (its sites' cells and their balls), and there equals the whole
  /// mesh's to rounding: the distributed front end's halos rely on it. Throws InputError for an
  /// index outside the mesh.
  MeanCurvature mean_curvature_at_sites(double r, double spacing, const std::vector<int>& vertices) const;
  /// Estimates with balls centred at arbitrary points (#P x 3): the seed is the face with the
  /// nearest centroid, found through a uniform grid of face centroids; N = that face's normal.
  CurvatureEstimates at_points(const Eigen::MatrixX3d& points, double r) const;
  /// Face whose centroid is nearest to x (grid hashing, expanding shells of cells).
  int nearest_face(const Eigen::Vector3d& x) const;

 private:
  void build_adjacency();
  /// mean_curvature_at_vertices' walk at the vertices vertex_order[at[k]] (vertex_order: every
  /// vertex in Z-order); the others get 0.
  MeanCurvature walk_mean_curvature(double r, const std::vector<int>& vertex_order, const std::vector<int>& at) const;
  /// Both mean_curvature_at_sites: every vertex when `only` is null.
  MeanCurvature sites_mean_curvature(double r, double spacing, const std::vector<int>* only) const;
  void compute_vertex_mu2();
  void estimate(const Eigen::Vector3d& x, double r, int seed, const Eigen::Vector3d& N, CurvatureEstimates& out,
                Eigen::Index i) const;

  bool interpolated_ = true;
  Eigen::MatrixX3d positions_, centroids_, face_normals_, vertex_normals_;
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> faces_;
  std::vector<int> neighbour_start_, neighbour_faces_;  // edge-adjacent faces of f, CSR, ascending
  std::vector<int> vertex_face_;                        // one incident face per vertex (-1 if none)
  // Uniform grid over the face centroids (cell size ~ mean edge length), CSR layout.
  Eigen::Vector3d grid_origin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i grid_dims_ = Eigen::Vector3i::Ones();
  double grid_cell_ = 1.0;
  std::vector<int> grid_start_, grid_faces_;
  void build_grid();
  // Edges (constant variant): vertex pair (a < b), mu1, and the face where it appears as a -> b.
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> edges_;
  std::vector<std::vector<int>> face_left_edges_;
  Eigen::VectorXd mu0_, mu1_, mu2_, edge_mu1_, vertex_mu2_;
  std::vector<Eigen::Matrix3d> edge_muxy_;
  std::vector<Eigen::Matrix3d> muxy_;
};

}  // namespace corrlap

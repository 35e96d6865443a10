#pragma once
// The ground truth of the cotan comparison (paper §3.4, docs/math.md §10.6; docs/studies.md): a
// triangle mesh refined by Loop subdivision, scaled to the unit box of the other studies, test
// functions and their cotan Laplacians on it, and their transfer to a digital surface by
// orthogonal projection and linear interpolation.
#include <Eigen/Core>
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/problems/test_functions.hpp>
#include <corrlap/surface/closest_point.hpp>
#include <memory>
#include <vector>

namespace corrlap {

struct CotanReference {
  Eigen::MatrixX3d positions;    ///< #V x 3, refined; bounding box centred at 0, longest side 2
  TriangleIndices triangles;     ///< #T x 3
  Eigen::MatrixX3d normals;      ///< #V x 3 unit vertex normals (area-weighted face normals)
  Eigen::MatrixXd f, laplacian;  ///< #V x #functions: f(x_v) and (M^-1 L f)_v, cotan L, Voronoi M
  Operators cotan;               ///< the cotan L and M of the refined mesh
  std::vector<const TestFunction*> functions;
  int input_vertices = 0, input_triangles = 0, subdivision_steps = 0;
  double scale = 1;                                  ///< world units of the input per unit here
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< bounding-box centre of the input
  std::shared_ptr<const TriangleLocator> locator;    ///< over positions / triangles
};

/// Triangulates `mesh` (polygons fanned), centres its bounding box at 0 and scales its longest side
/// to 2 (so that resolution N means h = 2 / N), Loop-subdivides it until it has `min_vertices`
/// vertices, then evaluates each function at the vertices and its cotan Laplacian. Throws
/// InputError for an empty mesh, one that is not closed (an edge without exactly two triangles),
/// zero-area triangles or vertices without normal.
CotanReference make_cotan_reference(const PolygonMesh& mesh, const std::vector<const TestFunction*>& functions,
                                    long long min_vertices);

/// How the test functions reach the digital surface. The paper interpolates the mesh's vertex
/// values; evaluating the function at the projected point instead removes the kinks of the
/// piecewise-linear interpolant, which the digital Laplacians see when the mesh's edges are not
/// much shorter than h (docs/studies.md, "cotan comparison"). The Laplacian is interpolated in both.
enum class ReferenceValues { Interpolated, AtFoot };

/// The forward evaluation on the reference itself, (M - dt L)^-1 L f (#V x #functions; dt = 0 gives
/// `laplacian`): with the study's dt, the truth carries the same diffusion bias dt Delta^2 f as the
/// digital results, which on a mesh with small features (the bunny's ears) is larger than the
/// differences between the operators (docs/studies.md, "cotan comparison").
Eigen::MatrixXd diffused_reference_laplacian(const CotanReference& reference, double dt);

/// The reference data at `points` (#P x 3, world units of a copy of the reference translated by
/// `shift`): each point is projected orthogonally onto the reference and the values at the corners
/// of the triangle it lands on are interpolated linearly (normals then renormalized).
struct ReferenceSamples {
  Eigen::MatrixXd f, laplacian;  ///< #P x #functions
  Eigen::MatrixX3d normals;      ///< #P x 3, unit
  double max_distance = 0;       ///< largest point-to-surface distance
};
/// `laplacian` (#V x #functions) is what is interpolated as the truth: reference.laplacian or
/// diffused_reference_laplacian.
ReferenceSamples sample_reference(const CotanReference& reference, const Eigen::MatrixXd& laplacian,
                                  const Eigen::MatrixX3d& points,
                                  const Eigen::Vector3d& shift = Eigen::Vector3d::Zero(),
                                  ReferenceValues values = ReferenceValues::Interpolated);

}  // namespace corrlap

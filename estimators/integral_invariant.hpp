#pragma once
// Integral-invariant (II) normal estimator (docs/math.md §7): covariance of the digital ball B(c, R) ∩ X at
// the inner and outer voxel of each surfel, averaged; normal = eigenvector of the smallest
// eigenvalue, oriented by the trivial normal.
#include <Eigen/Core>
#include <corrlap/core/progress.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace corrlap {

/// Parameters of docs/math.md §7. Euclidean radius R = k h^alpha, digital radius r_d = k h^(alpha-1).
/// These defaults are the paper's, for implicit shapes in their unit-size world (R = 3 h^0.33).
struct IIParams {
  double k = 3.0;       ///< "r-radius"
  double alpha = 0.33;  ///< reference Shortcuts default (the paper says 1/3)
  /// docs/math.md §7.2: where the ball sees more than the surface around its surfel (a rod or a
  /// wall thinner than the ball), estimate that surfel again with smaller radii. Off keeps §7 as
  /// the reference computes it.
  bool shrink_on_thin_parts = false;
};

/// §7.2's test: the II estimate of a surfel is ambiguous when the two smallest eigenvalues of its
/// covariance are within this ratio (no direction stands out: a rod thinner than the ball; a
/// half-ball, the ball on a smooth surface, has 0.30; a quarter-ball, on a right-angled edge, 0.64,
/// so such edges get small balls too, which keeps them from being rounded off by the ball) ...
inline constexpr double kIIAmbiguousEigenRatio = 0.6;
/// ... or when the normal is farther than this angle (degrees) from the sum of the trivial normals
/// of the faces around its face (the ball saw the far side of a part thinner than itself). A
/// staircase's surfel normals around a face stay within about 45 degrees of its true normal.
inline constexpr double kIIAmbiguousAngleDeg = 60.0;
/// Each retry multiplies the digital radius by this factor, down to one voxel.
inline constexpr double kIIShrinkFactor = 0.75;

/// The II radius, in voxels, for voxels that come from a file (a volume, a voxelized mesh):
/// R = 4 h. The paper's 3 h^0.33 assumes a unit-size shape and grows to tens of voxels on fine
/// volumes, wider than thin parts; a radius in voxels also gives the same result for a mesh whatever
/// its units. Chosen by measurement (docs/regularization.md, "Default radii").
inline constexpr double kVoxelIIRadius = 4.0;

/// The II parameters of an input: for an implicit shape the paper's (IIParams{}), for voxels from a
/// file k = kVoxelIIRadius voxels with alpha = 1 and shrink_on_thin_parts (real objects have rods
/// and walls thinner than any fixed ball). A given k, alpha or shrink_on_thin_parts replaces its default.
IIParams default_ii_params(bool implicit_shape, std::optional<double> k = {}, std::optional<double> alpha = {},
                           std::optional<bool> shrink_on_thin_parts = {});

/// Digital radius r_d = k * h^(alpha - 1) computed as the reference does (docs/math.md §7 step 1).
double ii_digital_radius(double h, const IIParams& params);

/// Exact (integer) moments of orders 0, 1, 2 of B(c, R) ∩ X relative to the centre c:
/// m0 = |Y|, m1 = sum (y - c), m2 = sum (y - c)(y - c)^T stored as xx, xy, xz, yy, yz, zz.
struct BallMoments {
  std::int64_t m0 = 0;
  std::int64_t m1[3] = {0, 0, 0};
  std::int64_t m2[6] = {0, 0, 0, 0, 0, 0};
  bool operator==(const BallMoments& o) const;
  /// Unnormalized covariance sum yy^T - (1/m0) (sum y)(sum y)^T (translation invariant); 0 if empty.
  Eigen::Matrix3d covariance() const;
};

/// Moments at each voxel centre, brute force over the kernel cube (slow; reference for tests).
std::vector<BallMoments> ii_moments_brute_force(const VoxelGrid& grid, double digital_radius, double h,
                                                const std::vector<Eigen::Vector3i>& centres);

/// Same moments, fast: every row of the grid is run-length encoded once (O(#runs) memory) and each
/// ball is swept row by row, a row's contribution being a closed-form sum over its runs clipped to
/// the ball's chord. Cost O(#centres * r_d^2), integer exact, parallel (TBB).
std::vector<BallMoments> ii_moments(const VoxelGrid& grid, double digital_radius, double h,
                                    const std::vector<Eigen::Vector3i>& centres, const ProgressFn& progress = {});

/// One II ball restricted to a component (docs/math.md §7.1): `centre` is the inner or the outer
/// voxel of a surfel and `seed` the surfel's inner voxel.
struct IIBall {
  Eigen::Vector3i centre, seed;
};

/// The moments of docs/math.md §7.1, readable form (the definition; slow, for tests): the voxels of
/// X are labelled by a flood fill of their 6-components, and each ball sums, over its kernel cube,
/// the voxels of the seed's component. Zero moments when the seed is not in X.
std::vector<BallMoments> ii_component_moments_brute_force(const VoxelGrid& grid, double digital_radius, double h,
                                                          const std::vector<IIBall>& balls);

/// Moments of several balls, each distinct (centre, component) stored once: ball i has moments[index[i]].
struct ComponentMoments {
  std::vector<BallMoments> moments;
  std::vector<std::uint32_t> index;
  const BallMoments& operator[](std::size_t i) const { return moments[index[i]]; }
};

/// Equal to ii_component_moments_brute_force, fast: the 6-components of X are labelled run by run
/// (a union-find over the runs of ii_moments that overlap on neighbouring rows), balls are grouped by
/// centre and component, and each group is one sweep of ii_moments over the runs of its component.
/// When X is one component, or no other component's bounding box is within reach of the ball,
/// that is the sweep of ii_moments itself. Integer exact, parallel (TBB).
ComponentMoments ii_component_moments(const VoxelGrid& grid, double digital_radius, double h,
                                      const std::vector<IIBall>& balls, const ProgressFn& progress = {});

/// The checks of ii_face_normals on the radius, for callers that hold only part of the grid (the
/// distributed normals): InputError when r_d < 1 or r_d > `extent` (the whole box's largest side,
/// in voxels), and when r_d >= `across` (the whole surface's bounding-box diagonal, in voxels: the
/// ball would cover the object from every surfel).
void ii_check_radius(int extent, double digital_radius);
void ii_check_radius_fits_object(double across, double digital_radius);

/// One face's II normal from the moments of its two balls (docs/math.md §7 steps 4-5): the
/// eigenvector of the smallest eigenvalue of the averaged covariance, oriented by the trivial
/// normal. ii_face_normals applies it to every face.
Eigen::Vector3d ii_normal_from_moments(const BallMoments& inner, const BallMoments& outer,
                                       const Eigen::Vector3d& trivial_normal);

/// docs/math.md §7.2's pieces, shared by ii_face_normals and the distributed normals (one policy).
///
/// The digital radius the balls start with, given the whole surface's bounding-box diagonal `across`
/// (voxels): with shrink_on_thin_parts, an object smaller than the ball (r_d >= across > 1) starts
/// below its own size, at max(1, kIIShrinkFactor across); otherwise at r_d.
struct IIStartRadius {
  double radius = 0.0;
  bool smaller_than_ball = false;
};
IIStartRadius ii_start_radius(double digital_radius, double across, bool shrink_on_thin_parts);

/// One face's estimate (ii_normal_from_moments) and §7.2's test of it against `around`, the unit sum
/// of the trivial normals around the face (zero: no test of the angle).
struct IIFaceEstimate {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  bool ambiguous = false;
};
IIFaceEstimate ii_estimate_from_moments(const BallMoments& inner, const BallMoments& outer,
                                        const Eigen::Vector3d& trivial_normal, const Eigen::Vector3d& around);

/// Per face (#F x 3), the unit sum of the trivial normals of the faces sharing a vertex with it
/// (itself included): the surface's direction around the face at the scale of one voxel. The sums
/// are of integer vectors, so any order of the faces gives the same bits.
Eigen::MatrixX3d ii_trivial_normals_around(const SurfelMesh& mesh);

/// The moments of the inner and outer balls (2 per face, in order) of the listed faces at a digital
/// radius, for ii_retry_thin_parts.
using IIFaceMoments = std::function<std::vector<BallMoments>(double radius, const std::vector<std::size_t>& faces)>;

/// docs/math.md §7.2 after the first estimate at `start`: the faces marked `ambiguous` are estimated
/// again with the radius times kIIShrinkFactor, down to one voxel, and take the first estimate that
/// is not ambiguous. A face that no radius resolves keeps its first estimate, except on an object
/// smaller than the ball, where it takes its trivial normals around (or its own trivial normal
/// when they point away). trivial, around, normals: #F x 3 in the caller's face order; ambiguous: #F.
void ii_retry_thin_parts(const IIStartRadius& start, const Eigen::MatrixX3d& trivial, const Eigen::MatrixX3d& around,
                         std::vector<std::uint8_t>& ambiguous, Eigen::MatrixX3d& normals, const IIFaceMoments& moments);

enum class IIMethod { Fast, BruteForce };

/// II normal per surfel/face (#F x 3), docs/math.md §7 (and §7.2 with params.shrink_on_thin_parts).
/// mesh.surfels must be present (mesh from voxels).
/// Throws InputError when the radius is below one voxel, larger than the box, or the mesh has no surfels.
Eigen::MatrixX3d ii_face_normals(const VoxelGrid& grid, const SurfelMesh& mesh, const IIParams& params = {},
                                 IIMethod method = IIMethod::Fast, const ProgressFn& progress = {});

/// Vertex normals: normalized sum of the incident II face normals (docs/math.md §1.5).
Eigen::MatrixX3d ii_vertex_normals(const VoxelGrid& grid, const SurfelMesh& mesh, const IIParams& params = {},
                                   const ProgressFn& progress = {});

}  // namespace corrlap

#pragma once
// The whole regularization of paper §4.1 on a digital surface (docs/math.md §9.2): mean curvature
// from the corrected curvature measures, a corrected L and M, one SPD solve. The CLI's
// `corrlap regularize` and the demo call this; regularize_positions is the solve alone.
#include <Eigen/Core>
#include <corrlap/core/config.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/progress.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/regularization/attachment_bias.hpp>
#include <corrlap/regularization/curvature_editing.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>
#include <corrlap/regularization/patch_bias.hpp>
#include <corrlap/regularization/solution_check.hpp>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace corrlap {

/// The smallest default curvature radius for voxels from a file (volumes, arrays, voxelized mesh
/// files), in voxels. 0.1 of the object's size is below one voxel on volumes under about 20 voxels
/// across: the ball then holds little more than the vertex's own faces, and where voxels touch along
/// an edge or at a corner H exceeded 1/h (2 to 10 vertices, up to 6/h); 2 voxels gave none, with
/// the same result elsewhere (docs/regularization.md, "Default radii").
inline constexpr double kVoxelMinCurvatureRadius = 2.0;

/// The paper's curvature radius for a unit-sized shape (0.1), as a fraction of the object size.
inline constexpr double kCurvatureRadiusFraction = 0.1;

/// The default spacing of the sites where the curvature ball is walked, as a fraction of the
/// curvature radius (CorrectedCurvature::mean_curvature_at_sites; docs/math.md §8.4): the other
/// vertices interpolate the sites' H. A quarter of the radius walks about one vertex in 15 at
/// the default radius and changes H by a few percent of its own error (docs/regularization.md,
/// "Curvature sites"); 0 walks every vertex.
inline constexpr double kCurvatureSiteSpacing = 0.25;

/// The default accuracy of the regularization's solve, in voxels (the mesh's grid step): the
/// area-weighted RMS error of every coordinate is provably below it (the bound of
/// regularize_positions_preconditioned). A thousandth of a voxel is a tenth of the smallest mean
/// distance to the truth measured on the analytic shapes (docs/comparison.md), and the actual error
/// is far below the bound (docs/regularization.md, "Solve accuracy").
inline constexpr double kRegularizationSolveAccuracy = 1e-3;

/// The default ball radius of the corrected curvature, the one rule of every command and binding
/// that computes curvature (regularize, reconstruct, curvature, the studies): `fraction` of the
/// object size, and for voxels from a file at least kVoxelMinCurvatureRadius voxels of side
/// `voxel`. Implicit shapes and meshes given as they are (voxels_from_file false) keep the
/// paper's rule. The II radius is decided from the same information (default_ii_params); the
/// pipeline's overloads on a LoadedSurface (pipeline/surface_defaults.hpp) decide voxels_from_file.
double default_curvature_radius(double size, double voxel, bool voxels_from_file,
                                double fraction = kCurvatureRadiusFraction);

struct RegularizationOptions {
  std::string method = "fem";  ///< a vertex-based discretization of the registry
  Config method_params;        ///< its parameters
  /// The paper's defaults are stated for unit-sized shapes (sphere1). For others they apply to
  /// the shape scaled by 1/size: alpha = alpha0 / (h size)^2 and a curvature radius of 0.1 size,
  /// which gives the same p' as regularizing the scaled shape and scaling back (L is scale
  /// invariant, M scales as size^2, H as 1/size). Unset: half the longest side of the bounding box.
  std::optional<double> size;
  /// Ball radius of the corrected mean curvature; unset: default_curvature_radius of the surface
  /// (0.1 size here, where the mesh alone does not say whether its voxels came from a file; the
  /// overloads on a LoadedSurface add the floor for volumes and mesh files).
  std::optional<double> curvature_radius;
  /// Spacing of the curvature's sites, a fraction of the curvature radius (0: every vertex).
  double curvature_spacing = kCurvatureSiteSpacing;
  double alpha0 = 10.0;  ///< alpha = alpha0 / (h size)^2; 0: no attachment (docs/math.md §9.3, paper Fig. 11)
  /// Choose alpha0 from the data, starting at alpha0 (docs/math.md §9.4, attachment_bias.hpp): solve,
  /// and while the result keeps away from the staircase's local mean and raising alpha0 brings it
  /// back, raise alpha0 and solve again (not from alpha0 = 0, no attachment asked, nor with curvature
  /// edits, which move the surface away on purpose). False: alpha0 as given (the paper's protocol).
  bool alpha0_auto = true;
  /// From this many vertices, the automatic choice first estimates the bias at alpha0 from patches
  /// and skips that solve when the estimate is far above the limit (patch_bias.hpp, docs/math.md §9.5).
  Eigen::Index patch_bias_min_vertices = kPatchBiasMinVertices;
  /// The h of alpha when the positions' error is not the mesh's own step (a subdivided coarse
  /// staircase, paper §4.2: the coarse voxel size); default the mesh's grid step.
  std::optional<double> alpha_step;
  double h_scale = 1.0;           ///< curvature editing (paper §4.3): H <- h_scale H ...
  std::optional<double> h_clamp;  ///< ... then clamped to [-h_clamp, h_clamp]
  /// Principal-curvature edits (paper §4.3, curvature_editing.hpp; k1 <= k2). When either is
  /// active, the regularization uses n' integrated from the edited S' and H = tr(S') / 2, to
  /// which h_scale and h_clamp then apply.
  PrincipalCurvatureEdit k1_edit, k2_edit;
  double normal_attachment = 1.0;  ///< attachment of n' to n (integrate_shape_operator)
  Config solver;                   ///< linear solver ("solver" key: backend name; default cholmod)
  /// The preconditioned solve stops when the error bound is below this many grid steps (0: to
  /// rounding). The direct solve is exact whatever it says.
  double solve_accuracy = kRegularizationSolveAccuracy;
  /// Progress of a long run: called on the calling thread before the mean curvature, the patch
  /// estimate of a large surface and each solve (every trial of the automatic alpha0) with a line
  /// saying what comes, e.g. "solving with alpha0 = 10". Empty: nothing is reported.
  ProgressLine report_stage;
};

/// Checks the options before any computation, in one wording for every front end (the CLI adds its
/// flags, Python its keywords): the method exists and defines its operators on vertices
/// (InputError "method" listing those that do), its parameters and the solver are valid, and
/// every real option is finite and in range (InputError naming it: size, curvature_radius,
/// curvature_spacing, alpha0,
/// alpha_step, h_scale, h_clamp, normal_attachment, k1/k2 edits). regularize_surface calls it.
void check_regularization_options(const RegularizationOptions& options);

/// The same, and what the options ask of this surface, still before the curvature and the solve:
/// alpha0 small enough for the attachment term alpha M_l p to be represented in the solve
/// (max_regularization_alpha; InputError "alpha0" naming the largest alpha0 this surface
/// allows). Front ends call it as soon as the surface is known, before writing anything.
void check_regularization_options(const SurfelMesh& mesh, const RegularizationOptions& options);

struct RegularizedSurface {
  SurfelMesh mesh;           ///< the input's faces and vertex order, regularized positions
  Eigen::VectorXd H;         ///< #V mean curvature used (after the edits)
  Eigen::MatrixX3d normals;  ///< #V x 3 unit normals n used: the input's, or n' after principal edits
  double h = 0.0, size = 1.0, curvature_radius = 0.0, alpha = 0.0;
  double alpha0 = 0.0;  ///< the alpha0 of the result (the options', or the automatic choice's)
  /// With alpha0_auto: every alpha0 tried and the bias of its result (or its estimate), in order;
  /// alpha0 names the one kept (an estimated trial that is kept is solved and listed again).
  std::vector<Alpha0Trial> alpha0_trials;
  std::string solver;  ///< backend name
  /// "preconditioned-cg" (regularize_positions_preconditioned, the default with a direct backend),
  /// "direct" (regularize_positions: with "cg", or when L is not negative semi-definite), or
  /// "unattached" (alpha0 = 0: regularize_positions_unattached).
  std::string solve_scheme;
  int solve_iterations = 0;  ///< CG iterations of the preconditioned scheme
  /// The preconditioned scheme's bound on the RMS error of the positions, in grid steps (0 for the
  /// direct scheme).
  double solve_error_bound = 0.0;
  double solve_residual = 0.0;  ///< relative residual |b - A q| / |b| of the solve, max over the coordinates
  SolutionCheck check;  ///< the result against the input (check_solution; no residual test at a proven accuracy)
  RegularizationEnergy energy_before, energy_after;  ///< at the input and at the result
  double curvature_seconds = 0.0, operators_seconds = 0.0, solve_seconds = 0.0;
  /// Of solve_seconds, the backend's analyses and factorizations (0 for iterative backends), and
  /// the last factor's size as the backend reports it (0 where it does not).
  double factorize_seconds = 0.0, factor_nonzeros = 0.0, factor_flops = 0.0;
  double normal_angle_change_deg = 0.0;  ///< mean angle between n' and n (0 without principal edits)
  std::vector<std::string> warnings;     ///< from the operators
};

/// The default object size: half the longest side of the bounding box (1 for the unit sphere, and
/// for a volume in world units, whose longest side spans 2).
double regularization_size(const SurfelMesh& mesh);

/// What regularize_surface uses besides the operators: the edited mean curvature and the normals of
/// the target (n, or n' after principal edits). It depends on the mesh, the normals and the
/// options' size, curvature radius and edits, not on the method: compute it once to regularize
/// with several methods (the corrected curvature is the slowest stage on large surfaces).
struct RegularizationCurvature {
  Eigen::VectorXd H;         ///< #V, after the edits
  Eigen::MatrixX3d normals;  ///< #V x 3
  double size = 1.0, curvature_radius = 0.0, normal_angle_change_deg = 0.0;
  double seconds = 0.0;
};
/// regularization_curvature's refusal of |H| > 1/h (the check is on the estimate, before the edits,
/// and skipped with h_clamp): InputError when `absurd` of the `total` vertices exceed it (up to
/// `worst`), naming a speck when the object is under 4 voxels across (`across`: its bounding box's
/// diagonal in voxels); nothing when absurd is 0. Every front end calls it with its own counts.
void check_curvature_resolvable(std::int64_t absurd, std::int64_t total, double worst, double h, double across);
/// Throws as regularize_surface for bad options, non-finite H or |H| > 1/h without a clamp.
RegularizationCurvature regularization_curvature(const SurfelMesh& mesh, const NormalFields& normals,
                                                 const RegularizationOptions& options = {});

/// Regularizes a closed surface with unit vertex normals (#V x 3, normals.vertex; the method's
/// own normals come from the same fields). Throws InputError for an open surface (naming its
/// boundary edge count), a method defined on faces, bad options (check_regularization_options,
/// before any computation); NumericalError when H is not finite or the result fails
/// check_solution; SolverError from the solve.
/// `curvature`: regularization_curvature(mesh, normals, options) computed before (reused across
/// methods; curvature_seconds is then 0), or null to compute it here.
RegularizedSurface regularize_surface(const SurfelMesh& mesh, const NormalFields& normals,
                                      const RegularizationOptions& options = {},
                                      const RegularizationCurvature* curvature = nullptr);

}  // namespace corrlap

#pragma once
// One entry point for the face-normal estimators used by the CLI and applications (docs/math.md §1.5, §7).
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <string>

namespace corrlap {

enum class NormalEstimator { Trivial, True, II, ConvolvedTrivial };
/// "trivial", "true", "ii", "convolved" -> estimator; InputError listing the valid names otherwise.
NormalEstimator parse_normal_estimator(const std::string& name);

/// Unit face normals (#F x 3). True needs `shape`; II needs `grid` (the voxels the mesh came from).
/// Throws InputError naming the missing input.
Eigen::MatrixX3d estimate_face_normals(NormalEstimator estimator, const SurfelMesh& mesh, const VoxelGrid* grid,
                                       const ImplicitShape* shape, const IIParams& ii = {},
                                       const ProgressFn& progress = {});

}  // namespace corrlap

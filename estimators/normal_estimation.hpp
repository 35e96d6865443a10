#pragma once
// Where normal fields come from (one vocabulary for the library, the CLI, Python and the studies)
// and the face-normal estimators behind it (docs/math.md §1.5, §7).
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <string>

namespace corrlap {

/// The source of a normal field. Names (parse_normal_source / to_string) in brackets.
enum class NormalSource {
  Auto,              ///< [auto] given normals if any, else true for implicit shapes, else II with voxels
  True,              ///< [true] true face normals of the implicit shape (docs/math.md §1.5)
  Exact,             ///< [exact] true face normals, and the shape's exact normal at each vertex (not their sum)
  II,                ///< [ii] integral-invariant face normals of the voxels (docs/math.md §7)
  Trivial,           ///< [trivial] surfel normals (docs/math.md §1.3)
  ConvolvedTrivial,  ///< [convolved] surfel normals averaged around each surfel (convolved_trivial_normals.hpp)
  Given,             ///< [given] only the normals the caller gives (files or matrices), never estimated
};
/// "auto", "true", "exact", "ii", "trivial", "convolved", "given" -> source; InputError (parameter
/// "normals") listing the valid names otherwise.
NormalSource parse_normal_source(const std::string& name);
const char* to_string(NormalSource source);

/// Unit face normals (#F x 3) of an estimating source (True and Exact: the true face normals; II,
/// Trivial, ConvolvedTrivial). True needs `shape`; II needs `grid` (the voxels the mesh came from).
/// Throws InputError (parameter "normals") naming the missing input, or for Auto and Given, which
/// name no estimator.
Eigen::MatrixX3d estimate_face_normals(NormalSource source, const SurfelMesh& mesh, const VoxelGrid* grid,
                                       const ImplicitShape* shape, const IIParams& ii = {},
                                       const ProgressFn& progress = {});

}  // namespace corrlap

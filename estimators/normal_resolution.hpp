#pragma once
// The one normal resolution of corrlap: turns "which normals" (a source, optional files or
// matrices) into the NormalFields an operator or the curvature needs (docs/math.md §1.5). The CLI,
// the Python module and the studies all call it, so a source means the same field everywhere:
// "true" vertex normals are the normalized sum of the incident true face normals (the reference's
// computeVertexNormalsFromFaceNormals, its vertex_normals_true.txt).
#include <Eigen/Core>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/estimators/normal_estimation.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <optional>
#include <string>

namespace corrlap {

/// Which normals, in library terms. Given normals (a file or a matrix per field, not both) come
/// first; `source` fills in what they leave missing.
struct NormalRequest {
  NormalSource source = NormalSource::Auto;
  std::string face_normals_file;    ///< one "nx ny nz" per face (file order); empty: none
  std::string vertex_normals_file;  ///< one "nx ny nz" per vertex; empty: none
  Eigen::MatrixX3d face_normals;    ///< in memory, #F x 3 (e.g. from Python); 0 rows: none
  Eigen::MatrixX3d vertex_normals;  ///< in memory, #V x 3; 0 rows: none
  /// II radius parameters (source II); unset: default_ii_params for the input (the paper's for an
  /// implicit shape, kVoxelIIRadius voxels for voxels without one).
  std::optional<IIParams> ii;
  ProgressFn progress;  ///< II progress (may be called from worker threads)
};

/// The normals a consumer needs (`need`, e.g. Discretization::required_normals()):
///  - given normals first: face normals (file or matrix) give face normals, vertex normals vertex normals;
///  - what is still missing comes from the source: face normals (true needs `shape`, II needs
///    `grid`, the voxels the mesh was extracted from), and vertex normals are always the normalized
///    sum of the incident face normals (docs/math.md §1.5), for every source and for given face
///    normals alike; the one exception is the source Exact, whose vertex normals are
///    exact_vertex_normals;
///  - need None: empty fields. Face: .face set. Vertex: .vertex set (and .face when computed).
/// Throws InputError naming what is missing (`what`, e.g. the method name, starts the message;
/// parameter "face_normals" or "vertex_normals"), or given normals whose row count does not match
/// the mesh. Unit length is left to the consumer (the discretizations' "normalize" parameter).
NormalFields resolve_normals(const SurfelMesh& mesh, NormalKind need, const NormalRequest& request,
                             const ImplicitShape* shape = nullptr, const VoxelGrid* grid = nullptr,
                             const std::string& what = "the method");

/// The source Auto stands for with these inputs (True with a shape, II with voxels), or Auto when
/// neither is available. Other sources are returned as they are.
NormalSource effective_normal_source(NormalSource source, const ImplicitShape* shape, const VoxelGrid* grid);

/// corrlap's "true vertex normals" (docs/math.md §1.5): the normalized sum of the incident true face
/// normals, what resolve_normals gives for the source True.
Eigen::MatrixX3d true_vertex_normals_from_faces(const ImplicitShape& shape, const SurfelMesh& mesh);

/// A different field: the exact normal of the shape at every vertex (radial on spheres, else the
/// gradient at the vertex's projection; true_vertex_normals of implicit_normals.hpp). What the
/// source Exact gives at vertices, not what "true" gives.
Eigen::MatrixX3d exact_vertex_normals(const ImplicitShape& shape, const SurfelMesh& mesh);

/// resolve_normals' check of the II radius parameters, for every front end that estimates II normals:
/// InputError "ii_radius" unless k is positive and finite, "ii_alpha" unless alpha is finite.
void check_ii_params(const IIParams& ii);

namespace detail {
/// resolve_normals' check of II vertex normals (the normalized sums of the faces'): returns when
/// none is zero, else throws InputError, parameter "ii_radius" when the radius reaches across the
/// part of the first zero normal (half its thinnest side or more), "normals" otherwise.
void check_ii_vertex_normals(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals, const IIParams& ii);
}  // namespace detail

}  // namespace corrlap

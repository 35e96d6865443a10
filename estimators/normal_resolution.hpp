#pragma once
// One place that turns "which normals" (a source name, optional files) into the NormalFields an
// operator or the curvature needs (docs/math.md §1.5). Every CLI command calls it, so a source means the
// same field everywhere: "true" vertex normals are the normalized sum of the incident true face
// normals (the reference's computeVertexNormalsFromFaceNormals, its vertex_normals_true.txt).
#include <Eigen/Core>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <string>

namespace corrlap {

/// Where normals come from when no file gives them.
enum class NormalSource {
  Auto,              ///< true for implicit shapes, else II when voxels are given, else none (an error)
  True,              ///< true face normals of the implicit shape (docs/math.md §1.5)
  II,                ///< integral-invariant face normals of the voxels (docs/math.md §7)
  Trivial,           ///< surfel normals (docs/math.md §1.3)
  ConvolvedTrivial,  ///< surfel normals averaged around each surfel (convolved_trivial_normals.hpp)
};
/// "auto", "true", "ii", "trivial", "convolved" -> source; InputError listing the valid names otherwise.
NormalSource parse_normal_source(const std::string& name);
const char* to_string(NormalSource source);

struct NormalRequest {
  NormalSource source = NormalSource::Auto;
  std::string face_normals_file;    ///< one "nx ny nz" per face (file order); empty: none
  std::string vertex_normals_file;  ///< one "nx ny nz" per vertex; empty: none
  IIParams ii;                      ///< II radius parameters (source II)
  ProgressFn progress;              ///< II progress (may be called from worker threads)
};

/// The normals a consumer needs (`need`, e.g. Discretization::required_normals()):
///  - files first: a face file gives face normals, a vertex file vertex normals;
///  - what is still missing comes from the source: face normals (true needs `shape`, II needs
///    `grid`, the voxels the mesh was extracted from), and vertex normals are always the normalized
///    sum of the incident face normals (docs/math.md §1.5), for every source and for a face file alike;
///  - need None: empty fields. Face: .face set. Vertex: .vertex set (and .face when computed).
/// Throws InputError naming what is missing (`what`, e.g. the method name, starts the message),
/// or a file whose row count does not match the mesh. Unit length is left to the consumer (the
/// discretizations' "normalize" parameter).
NormalFields resolve_normals(const SurfelMesh& mesh, NormalKind need, const NormalRequest& request,
                             const ImplicitShape* shape = nullptr, const VoxelGrid* grid = nullptr,
                             const std::string& what = "the method");

/// The source Auto stands for with these inputs (True with a shape, II with voxels), or Auto when
/// neither is available.
NormalSource effective_normal_source(NormalSource source, const ImplicitShape* shape, const VoxelGrid* grid);

/// corrlap's "true vertex normals" (docs/math.md §1.5): the normalized sum of the incident true face
/// normals, what resolve_normals gives for the source True.
Eigen::MatrixX3d true_vertex_normals_from_faces(const ImplicitShape& shape, const SurfelMesh& mesh);

/// A different field: the exact normal of the shape at every vertex (radial on spheres, else the
/// gradient at the vertex's projection; true_vertex_normals of implicit_normals.hpp). Not what
/// --normals true gives; for experiments that need the exact vertex normal.
Eigen::MatrixX3d exact_vertex_normals(const ImplicitShape& shape, const SurfelMesh& mesh);

}  // namespace corrlap

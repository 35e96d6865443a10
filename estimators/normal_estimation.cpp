#include "normal_estimation.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/estimators/convolved_trivial_normals.hpp>
#include <corrlap/estimators/implicit_normals.hpp>

namespace corrlap {

NormalSource parse_normal_source(const std::string& name) {
  for (const NormalSource s : {NormalSource::Auto, NormalSource::True, NormalSource::Exact, NormalSource::II,
                               NormalSource::Trivial, NormalSource::ConvolvedTrivial, NormalSource::Given})
    if (name == to_string(s)) return s;
  throw InputError("unknown normal source '" + name + "' (valid: auto, true, exact, ii, trivial, convolved, given)",
                   "normals");
}

const char* to_string(NormalSource source) {
  switch (source) {
    case NormalSource::Auto:
      return "auto";
    case NormalSource::True:
      return "true";
    case NormalSource::Exact:
      return "exact";
    case NormalSource::II:
      return "ii";
    case NormalSource::Trivial:
      return "trivial";
    case NormalSource::ConvolvedTrivial:
      return "convolved";
    case NormalSource::Given:
      return "given";
  }
  return "?";
}

Eigen::MatrixX3d estimate_face_normals(NormalSource source, const SurfelMesh& mesh, const VoxelGrid* grid,
                                       const ImplicitShape* shape, const IIParams& ii, const ProgressFn& progress) {
  switch (source) {
    case NormalSource::Trivial:
      return mesh.face_normals_from_positions();
    case NormalSource::True:
    case NormalSource::Exact:
      if (!shape) throw InputError(std::string(to_string(source)) + " normals need an implicit shape", "normals");
      return true_face_normals(*shape, mesh);
    case NormalSource::II:
      if (!grid || !mesh.has_surfels())
        throw InputError("II normals need voxels (an implicit shape, a volume or a voxelized mesh), not a quad mesh",
                         "normals");
      return ii_face_normals(*grid, mesh, ii, IIMethod::Fast, progress);
    case NormalSource::ConvolvedTrivial:
      return convolved_trivial_normals(mesh);
    case NormalSource::Auto:
    case NormalSource::Given:
      break;
  }
  throw InputError(std::string("normal source '") + to_string(source) + "' names no estimator", "normals");
}

}  // namespace corrlap

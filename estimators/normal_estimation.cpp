#include "normal_estimation.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/estimators/convolved_trivial_normals.hpp>
#include <corrlap/estimators/implicit_normals.hpp>

namespace corrlap {

NormalEstimator parse_normal_estimator(const std::string& name) {
  if (name == "trivial") return NormalEstimator::Trivial;
  if (name == "true") return NormalEstimator::True;
  if (name == "ii") return NormalEstimator::II;
  if (name == "convolved") return NormalEstimator::ConvolvedTrivial;
  throw InputError("unknown normal estimator '" + name + "' (valid: trivial, true, ii, convolved)");
}

Eigen::MatrixX3d estimate_face_normals(NormalEstimator estimator, const SurfelMesh& mesh, const VoxelGrid* grid,
                                       const ImplicitShape* shape, const IIParams& ii, const ProgressFn& progress) {
  switch (estimator) {
    case NormalEstimator::Trivial:
      return mesh.face_normals_from_positions();
    case NormalEstimator::True:
      if (!shape) throw InputError("true normals need an implicit shape (--shape or --polynomial)");
      return true_face_normals(*shape, mesh);
    case NormalEstimator::II:
      if (!grid || !mesh.has_surfels())
        throw InputError("II normals need voxels (--shape, --polynomial or --volume), not a mesh file");
      return ii_face_normals(*grid, mesh, ii, IIMethod::Fast, progress);
    case NormalEstimator::ConvolvedTrivial:
      return convolved_trivial_normals(mesh);
  }
  throw InputError("unknown normal estimator");
}

}  // namespace corrlap

#pragma once
// Validation of the normal field given to a corrected discretization, and the policy for
// normals inconsistent with the surfel orientation (u . n_triv <= 0).
#include <Eigen/Core>
#include <corrlap/core/config.hpp>
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/parameters.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <string>
#include <vector>

namespace corrlap {

/// The parameters shared by every corrected method: orientation, clamp_min, normalize. The default
/// orientation policy is clamp: "warn" computes exactly what the reference computes, but one corner
/// with u.n slightly below 0 can give L a large positive eigenvalue (docs/discretizations.md), which
/// no user asking for an operator wants.
const ParameterList& normal_policy_parameters();
/// "error" | "warn" | "clamp"; InputError otherwise.
OrientationPolicy parse_orientation_policy(const std::string& text);

/// Outcome of the orientation check.
struct OrientationReport {
  int checked = 0;       ///< faces (face normals) or face corners (vertex normals)
  int inconsistent = 0;  ///< u . n_triv <= 0
  Eigen::Index worst_face = -1, worst_corner = -1;
  double worst_dot = 1.0;
  std::string summary(const std::string& method) const;
};

/// Normals ready for the kernels: the caller's own matrix when nothing had to change (no copy:
/// at h = 0.005 a copy is 18 MB of fresh memory per call), else a corrected copy. Holds a pointer
/// to the caller's NormalFields in the first case, so it must not outlive them.
class PreparedNormals {
 public:
  explicit PreparedNormals(const Eigen::MatrixX3d& borrowed) : borrowed_(&borrowed) {}
  explicit PreparedNormals(Eigen::MatrixX3d&& owned) : owned_(std::move(owned)) {}
  const Eigen::MatrixX3d& matrix() const { return borrowed_ ? *borrowed_ : owned_; }
  bool is_copy() const { return borrowed_ == nullptr; }

 private:
  Eigen::MatrixX3d owned_;
  const Eigen::MatrixX3d* borrowed_ = nullptr;
};

/// Returns the normals the kernels must use (warnings and contract_risk go to `ops`):
///  - checks count, finiteness, non-zero length and unit length (parameter "normalize": rescale instead);
///  - orientation: for face normals u_f . n_f, for vertex normals u_v . n_f at every corner of f;
///    policy "clamp" (default) raises u . n_f to `clamp_min` (default 0.05), renormalizes and appends
///    a warning with the count and the worst element; "warn" keeps the normals exactly as given,
///    appends a warning saying what that breaks and sets ops.contract_risk; "error" throws naming
///    the worst element.
///  - normals pointing inward on more than half of the elements are rejected under every policy
///    (flipped orientation: the mass matrix would be negative).
PreparedNormals prepare_normals(const SurfelMesh& mesh, const NormalFields& normals, NormalKind kind,
                                const ParameterValues& params, const std::string& method, Operators& ops,
                                OrientationReport* report = nullptr);

/// Trivial (outward) unit normal of every face: from the surfel data when present, else from
/// the corner positions (docs/math.md §1.5; equal on surfels).
Eigen::MatrixX3d trivial_face_normals(const SurfelMesh& mesh);

}  // namespace corrlap

#include "normal_policy.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <sstream>

namespace corrlap {

const ParameterList& normal_policy_parameters() {
  static const ParameterList list = {
      Parameter::choice("orientation", {"clamp", "warn", "error"},
                        "normals with u.n <= 0 on a surfel: clamp (raise u.n to clamp_min) | warn (compute as "
                        "given: L, M may break their contract) | error"),
      Parameter::real("clamp_min", 0.05, "with orientation=clamp: smallest allowed u.n before renormalization")
          .above(0.0)
          .below(1.0),
      Parameter::boolean("normalize", false, "rescale non-unit normals instead of rejecting them")};
  return list;
}

OrientationPolicy parse_orientation_policy(const std::string& text) {
  if (text == "error") return OrientationPolicy::Error;
  if (text == "warn") return OrientationPolicy::Warn;
  if (text == "clamp") return OrientationPolicy::Clamp;
  throw InputError("orientation policy '" + text + "': expected error, warn or clamp");
}

std::string OrientationReport::summary(const std::string& method) const {
  std::ostringstream os;
  os.precision(6);
  os << method << ": " << inconsistent << " of " << checked << (worst_corner >= 0 ? " face corners" : " faces")
     << " have normals with u.n <= 0 (worst: face " << worst_face;
  if (worst_corner >= 0) os << " corner " << worst_corner;
  os << ", u.n = " << worst_dot << ")";
  return os.str();
}

Eigen::MatrixX3d trivial_face_normals(const SurfelMesh& mesh) {
  if (!mesh.has_surfels()) return mesh.face_normals_from_positions();
  Eigen::MatrixX3d n(mesh.num_faces(), 3);
  tbb::parallel_for(0, mesh.num_faces(),
                    [&](int f) { n.row(f) = mesh.surfels[std::size_t(f)].trivial_normal().transpose(); });
  return n;
}

PreparedNormals prepare_normals(const SurfelMesh& mesh, const NormalFields& normals, NormalKind kind,
                                const ParameterValues& params, const std::string& method, Operators& ops,
                                OrientationReport* out_report) {
  std::vector<std::string>& warnings = ops.warnings;
  if (kind == NormalKind::None) return PreparedNormals(Eigen::MatrixX3d());
  const bool face = kind == NormalKind::Face;
  const Eigen::MatrixX3d& given = face ? normals.face : normals.vertex;
  const std::string what = method + ": " + (face ? "face" : "vertex") + " normals";
  if (given.rows() == 0)
    throw InputError(method + " needs " + (face ? "one normal per face" : "one normal per vertex") + " (none given)");
  const Eigen::Index expected = face ? mesh.num_faces() : mesh.num_vertices();
  // Copy only when the normals change (normalize here, clamp below).
  PreparedNormals result(given);
  if (params.boolean("normalize")) {
    Eigen::MatrixX3d u = given;
    validate_normals(u, expected, what, true);
    result = PreparedNormals(std::move(u));
  } else {
    check_normals(given, expected, what);
  }
  const Eigen::MatrixX3d& u = result.matrix();
  const OrientationPolicy policy = parse_orientation_policy(params.choice("orientation"));
  const double clamp_min = params.real("clamp_min");

  // Trivial normals on the fly from the surfels (no F x 3 matrix); from positions otherwise.
  const Eigen::MatrixX3d from_positions = mesh.has_surfels() ? Eigen::MatrixX3d() : mesh.face_normals_from_positions();
  const auto trivial = [&](int f) -> Eigen::Vector3d {
    return mesh.has_surfels() ? mesh.surfels[std::size_t(f)].trivial_normal()
                              : Eigen::Vector3d(from_positions.row(f).transpose());
  };
  // Parallel check; the reduction keeps the first minimum in face order, like a serial scan.
  struct Scan {
    int inconsistent = 0;
    double worst_dot = 1.0;
    Eigen::Index worst_face = -1, worst_corner = -1;
    void note(Eigen::Index f, Eigen::Index corner, double d) {
      ++inconsistent;
      if (worst_face < 0 || d < worst_dot) {
        worst_dot = d;
        worst_face = f;
        worst_corner = corner;
      }
    }
  };
  const Scan scan = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<int>(0, mesh.num_faces(), 4096), Scan{},
      [&](const tbb::blocked_range<int>& range, Scan acc) {
        for (int f = range.begin(); f != range.end(); ++f) {
          const Eigen::Vector3d n = trivial(f);
          if (face) {
            const double d = u.row(f).dot(n);
            if (!(d > 0.0)) acc.note(f, -1, d);
          } else {
            for (int c = 0; c < 4; ++c) {
              const double d = u.row(mesh.faces(f, c)).dot(n);
              if (!(d > 0.0)) acc.note(f, c, d);
            }
          }
        }
        return acc;
      },
      [](Scan left, const Scan& right) {
        const int count = left.inconsistent + right.inconsistent;
        if (right.worst_face >= 0 && (left.worst_face < 0 || right.worst_dot < left.worst_dot)) left = right;
        left.inconsistent = count;
        return left;
      });
  OrientationReport r;
  r.checked = face ? mesh.num_faces() : 4 * mesh.num_faces();
  r.inconsistent = scan.inconsistent;
  r.worst_dot = scan.worst_dot;
  r.worst_face = scan.worst_face;
  r.worst_corner = scan.worst_corner;
  if (!face && r.inconsistent == 0) r.worst_corner = -1;
  if (out_report) *out_report = r;
  if (r.inconsistent == 0) return result;
  if (2 * r.inconsistent > r.checked)
    throw InputError(r.summary(method) +
                     ": on more than half of them the normals point inward or lie in the surfels' planes: given "
                     "normals are flipped (flip them or the face orientation); estimated ones did not see the surface "
                     "(II normals whose ball is as large as the object: a smaller ii_radius or a finer resolution)");
  switch (policy) {
    case OrientationPolicy::Error:
      throw InputError(r.summary(method));
    case OrientationPolicy::Warn:
      // As given, like the reference: a corrected area u.n <= 0 makes that element's measure
      // non-positive (docs/math.md §4.2), so the assembled operators lose their sign guarantees.
      ops.contract_risk = r.summary(method) + ", used as given (orientation=warn)";
      warnings.push_back(r.summary(method) +
                         "; used as given (orientation=warn): L may not be negative semi-definite nor M positive "
                         "definite, so solvers may fail; orientation=clamp (the default) repairs these normals");
      return result;
    case OrientationPolicy::Clamp:
      break;
  }
  Eigen::MatrixX3d clamped = u;
  const Eigen::MatrixX3d n = trivial_face_normals(mesh);
  // Clamp: push u toward the trivial normal until u.n >= clamp_min on every face (for vertex
  // normals: every incident face), renormalizing after each correction.
  for (int pass = 0; pass < 8; ++pass) {
    bool changed = false;
    for (int f = 0; f < mesh.num_faces(); ++f)
      for (int c = 0; c < (face ? 1 : 4); ++c) {
        const Eigen::Index row = face ? f : mesh.faces(f, c);
        const double d = clamped.row(row).dot(n.row(f));
        if (d < clamp_min - 1e-12) {
          clamped.row(row) += (clamp_min - d + 1e-9) * n.row(f);
          clamped.row(row).normalize();
          changed = true;
        }
      }
    if (!changed) break;
  }
  std::ostringstream note;
  note << r.summary(method) << "; raised to u.n >= " << clamp_min
       << " and renormalized (orientation=clamp, the default; orientation=warn uses them as given)";
  warnings.push_back(note.str());
  return PreparedNormals(std::move(clamped));
}

}  // namespace corrlap

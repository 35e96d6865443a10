#include "corrected_fem.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/detail/fem_kernel.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>

namespace corrlap {

namespace {
// a . b and a x b component by component: the order of the fast kernel (corrected_fem_fast.cpp),
// so that both give the same bits.
double dot3(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return a.x() * b.x() + a.y() * b.y() + a.z() * b.z();
}
Eigen::Vector3d cross3(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return {a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x()};
}
// a / |a|, or a itself when it is zero.
Eigen::Vector3d normalized3(const Eigen::Vector3d& a) {
  const double n2 = dot3(a, a);
  if (!(n2 > 0.0)) return a;
  const double n = std::sqrt(n2);
  return {a.x() / n, a.y() / n, a.z() / n};
}
}  // namespace

FemLocalFrame corrected_fem_local_frame(const QuadCorners& x, const Eigen::Vector3d& u) {
  // docs/math.md §4.2: e_s = normalize(x1 - x0), e_t = normalize(x3 - x0), nu = (e1 x e3) / area.
  const Eigen::Vector3d e1 = (x.row(1) - x.row(0)).transpose();
  const Eigen::Vector3d e3 = (x.row(3) - x.row(0)).transpose();
  const Eigen::Vector3d c = cross3(e1, e3);
  FemLocalFrame fr;
  fr.area = std::sqrt(dot3(c, c));  // |(x1 - x0) x (x3 - x0)| (docs/math.md §4.4)
  const Eigen::Vector3d nu(c.x() / fr.area, c.y() / fr.area, c.z() / fr.area);
  fr.u_local = Eigen::Vector3d(dot3(u, normalized3(e1)), dot3(u, normalized3(e3)), dot3(u, nu));
  return fr;
}

Eigen::Matrix4d corrected_fem_local_stiffness(const Eigen::Vector3d& u) {
  // docs/math.md §4.3, DGtal form (valid even when u is slightly off unit length), u = (x, y, z):
  // with s_x = 1 - x^2, s_y = 1 - y^2 and eta = x y / (2 z),
  //   K_00 = K_22 = eta + (s_x + s_y) / (3 z),      K_11 = K_33 = K_00 - 2 eta,
  //   K_01 = K_23 = (s_x - 2 s_y) / (6 z),          K_03 = K_12 = (s_y - 2 s_x) / (6 z),
  //   K_02 = -eta - (s_x + s_y) / (6 z),            K_13 = K_02 + 2 eta.
  // Divisions by z as products with 1 / z, in the fast kernel's order (same bits).
  const double x = u.x(), y = u.y(), z = u.z();
  const double inv_z = 1.0 / z;
  const double sx = 1.0 - x * x, sy = 1.0 - y * y;
  const double eta = x * y * 0.5 * inv_z;
  const double k00 = eta + (sx + sy) / 3.0 * inv_z;
  const double k01 = (-2.0 * sy + sx) / 6.0 * inv_z;
  const double k03 = (-2.0 * sx + sy) / 6.0 * inv_z;
  const double k02 = -eta - (sx + sy) / 6.0 * inv_z;
  const double k11 = k00 - 2.0 * eta, k13 = k02 + 2.0 * eta;
  Eigen::Matrix4d K;
  K << k00, k01, k02, k03,  //
      k01, k11, k03, k13,   //
      k02, k03, k00, k01,   //
      k03, k13, k01, k11;
  return K;
}

Eigen::Matrix4d corrected_fem_local_mass(double area, double z) {
  // docs/math.md §4.4: (area z / 36) [4 2 1 2; 2 4 2 1; 1 2 4 2; 2 1 2 4].
  Eigen::Matrix4d W;
  W << 4, 2, 1, 2,  //
      2, 4, 2, 1,   //
      1, 2, 4, 2,   //
      2, 1, 2, 4;
  return (area * z / 36.0) * W;
}

Eigen::Matrix4d corrected_fem_local_lumped_mass(double area, double z) {
  // docs/math.md §4.4: (area z / 4) I.
  return Eigen::Matrix4d::Identity() * (area * z / 4.0);
}

namespace {

class CorrectedFem final : public Discretization {
 public:
  std::string name() const override { return "fem"; }
  NormalKind required_normals() const override { return NormalKind::Face; }
  const ParameterList& parameters() const override {
    static const ParameterList list =
        ParameterList{
            Parameter::choice("mass", {"full", "lumped"}, "mass matrix: full (consistent) | lumped (diagonal)", "§4.4"),
            extras_parameter()}
            .append(normal_policy_parameters());
    return list;
  }

  // L and M are filled by the fast assembly (corrected_fem_fast.cpp), whose resize keeps the
  // matrices' allocated storage: with a reused `ops` nothing is allocated for them.
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& config,
                     const QuadPattern* pattern, Operators& ops) const override {
    const ParameterValues params = parameters().read(config, "fem");
    const std::string mass = params.choice("mass");
    const bool extras = params.boolean("extras");
    check_quad_mesh(mesh, "fem");

    reset_for_reuse(ops);
    const PreparedNormals prepared = prepare_normals(mesh, normals, NormalKind::Face, params, "fem", ops);
    const Eigen::MatrixX3d& u = prepared.matrix();
    detail::corrected_fem_fast_assembly(mesh, u, pattern, mass == "lumped", extras, ops);
    if (extras) ops.D0 = global_d0(build_edges(mesh), mesh.num_vertices());
  }
};

}  // namespace

std::unique_ptr<Discretization> make_corrected_fem() { return std::make_unique<CorrectedFem>(); }

}  // namespace corrlap

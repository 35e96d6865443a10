#include "corrected_fem.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <corrlap/core/error.hpp>

#include "normal_policy.hpp"
#include "quad_row_gather.hpp"

namespace corrlap {

FemLocalFrame corrected_fem_local_frame(const QuadCorners& x, const Eigen::Vector3d& u) {
  // spec §4.2: e_s = normalize(x1 - x0), e_t = normalize(x3 - x0), nu = normalize(e1 x e3).
  const Eigen::Vector3d d1 = (x.row(1) - x.row(0)).transpose();
  const Eigen::Vector3d d3 = (x.row(3) - x.row(0)).transpose();
  const Eigen::Vector3d c = d1.cross(d3);
  FemLocalFrame fr;
  fr.area = c.norm();
  fr.u_local = Eigen::Vector3d(u.dot(d1.normalized()), u.dot(d3.normalized()), u.dot(c / fr.area));
  return fr;
}

namespace {
// Stiffness written straight into a row-major 4x4 buffer, scaled by `scale` (-1 for L_f).
inline void fem_stiffness_into(double x, double y, double z, double scale, double* K) {
  // spec §4.3, DGtal form (valid even when u is slightly off unit length).
  const double sx = 1.0 - x * x, sy = 1.0 - y * y, eta = x * y / (2.0 * z);
  const double self = eta + (sx + sy) / (3.0 * z);
  const double o1 = (-2.0 * sy + sx) / (6.0 * z);
  const double o2 = (-2.0 * sx + sy) / (6.0 * z);
  const double o = -eta - (sx + sy) / (6.0 * z);
  const double s2 = self - 2.0 * eta, oe = o + 2.0 * eta;
  const double v[16] = {self, o1, o, o2,  //
                        o1, s2, o2, oe,   //
                        o, o2, self, o1,  //
                        o2, oe, o1, s2};
  for (int k = 0; k < 16; ++k) K[k] = scale * v[k];
}

// Row i of L_f = -K_f from g = (x, y, z, area) (spec §4.3 pattern).
inline void fem_stiffness_row(const double* g, int i, double* row) {
  const double x = g[0], y = g[1], iz = 1.0 / g[2];
  const double sx = 1.0 - x * x, sy = 1.0 - y * y, eta = x * y * 0.5 * iz;
  const double self = eta + (sx + sy) / 3.0 * iz;
  const double o1 = (-2.0 * sy + sx) / 6.0 * iz;
  const double o2 = (-2.0 * sx + sy) / 6.0 * iz;
  const double o = -eta - (sx + sy) / 6.0 * iz;
  switch (i) {
    case 0: row[0] = -self, row[1] = -o1, row[2] = -o, row[3] = -o2; break;
    case 1: row[0] = -o1, row[1] = -(self - 2.0 * eta), row[2] = -o2, row[3] = -(o + 2.0 * eta); break;
    case 2: row[0] = -o, row[1] = -o2, row[2] = -self, row[3] = -o1; break;
    default: row[0] = -o2, row[1] = -(o + 2.0 * eta), row[2] = -o1, row[3] = -(self - 2.0 * eta); break;
  }
}

inline void fem_mass_into(double area, double z, bool lumped, double* M) {
  if (lumped) {
    const double d = area * z / 4.0;
    for (int k = 0; k < 16; ++k) M[k] = (k % 5 == 0) ? d : 0.0;
    return;
  }
  static const double w[16] = {4, 2, 1, 2, 2, 4, 2, 1, 1, 2, 4, 2, 2, 1, 2, 4};
  const double s = area * z / 36.0;
  for (int k = 0; k < 16; ++k) M[k] = s * w[k];
}
}  // namespace

Eigen::Matrix4d corrected_fem_local_stiffness(const Eigen::Vector3d& u) {
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> K;
  fem_stiffness_into(u.x(), u.y(), u.z(), 1.0, K.data());
  return K;
}

Eigen::Matrix4d corrected_fem_local_mass(double area, double z) {
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> M;
  fem_mass_into(area, z, false, M.data());
  return M;
}

Eigen::Matrix4d corrected_fem_local_lumped_mass(double area, double z) {
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> M;
  fem_mass_into(area, z, true, M.data());
  return M;
}

namespace {

class CorrectedFem final : public Discretization {
 public:
  std::string name() const override { return "fem"; }
  NormalKind required_normals() const override { return NormalKind::Face; }
  std::vector<ParameterInfo> parameters() const override {
    std::vector<ParameterInfo> p = {{"mass", "full", "mass matrix: full (consistent) | lumped (diagonal), spec §4.4"},
                                    extras_parameter()};
    for (auto& q : normal_policy_parameters()) p.push_back(q);
    return p;
  }

  Operators assemble(const SurfelMesh& mesh, const NormalFields& normals, const Config& params) const override {
    std::vector<std::string> keys;
    for (const auto& p : parameters()) keys.push_back(p.name);
    params.check_keys(keys, "fem parameters");
    const std::string mass = params.get_string("mass", "full");
    if (mass != "full" && mass != "lumped") throw InputError("fem: mass '" + mass + "': expected full or lumped");
    const bool extras = params.get_bool("extras", false);
    check_quad_mesh(mesh, "fem");

    Operators ops;
    const Eigen::MatrixX3d u = prepare_normals(mesh, normals, NormalKind::Face, params, "fem", ops.warnings);
    const int F = mesh.num_faces();
    // Per-face (x, y, z, area): the only data the local matrices depend on (spec §4.3, §4.4).
    std::vector<double> geo(std::size_t(F) * 4);
    tbb::parallel_for(tbb::blocked_range<int>(0, F, 2048), [&](const tbb::blocked_range<int>& r) {
      for (int f = r.begin(); f != r.end(); ++f) {
        const FemLocalFrame fr = corrected_fem_local_frame(quad_corners(mesh, f), u.row(f).transpose());
        double* g = geo.data() + std::size_t(f) * 4;
        g[0] = fr.u_local.x();
        g[1] = fr.u_local.y();
        g[2] = fr.u_local.z();
        g[3] = fr.area;
      }
    });
    // Fused kernel + vertex-row gather: the local matrices depend only on (x, y, z, area), so each
    // row is computed where it is summed and every matrix entry is written once (memory-bound).
    const detail::VertexCorners vc = detail::vertex_corners(mesh);
    const bool lumped = mass == "lumped";
    auto lumped_mass = [&] {
      return detail::gather_corner_diagonal(mesh, vc, [&](int f, int) {
        const double* g = geo.data() + std::size_t(f) * 4;
        return g[3] * g[2] / 4.0;
      });
    };
    if (lumped) {
      detail::gather_quad_rows<1>(mesh, vc, [&](int f, int i, double* rows) { fem_stiffness_row(geo.data() + std::size_t(f) * 4, i, rows); },
                                  {&ops.L});
      ops.M = lumped_mass();
    } else {
      detail::gather_quad_rows<2>(
          mesh, vc,
          [&](int f, int i, double* rows) {
            const double* g = geo.data() + std::size_t(f) * 4;
            fem_stiffness_row(g, i, rows);
            // spec §4.4 consistent mass row i: (area z / 36) [4 2 1 2] rotated.
            const double sc = g[3] * g[2] / 36.0;
            static const double w[4] = {4, 2, 1, 2};
            for (int j = 0; j < 4; ++j) rows[4 + j] = sc * w[(j - i + 4) & 3];
          },
          {&ops.L, &ops.M});
    }
    if (extras) {
      ops.M_lumped = lumped ? ops.M : lumped_mass();
      ops.D0 = global_d0(build_edges(mesh), mesh.num_vertices());
    }
    return ops;
  }
};

}  // namespace

std::unique_ptr<Discretization> make_corrected_fem() { return std::make_unique<CorrectedFem>(); }

}  // namespace corrlap

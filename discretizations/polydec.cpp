#include "polydec.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/assembly/detail/quad_pattern_access.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>

namespace corrlap {

QuadCorners polydec_project_corners(const QuadCorners& x, const Eigen::Vector3d& u) {
  QuadCorners p;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d v = x.row(k).transpose();
    p.row(k) = (v - u.dot(v) * u).transpose();  // docs/math.md §2.5
  }
  return p;
}

PolyDecLocal polydec_local(const QuadCorners& X, double lambda) {
  // docs/math.md §2.2 with n = 4.
  const Eigen::Matrix4d& D = quad_difference();
  PolyDecLocal r;
  Eigen::Matrix<double, 4, 3> E, B;
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), c = Eigen::Vector3d::Zero();
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    const Eigen::Vector3d xi = X.row(i).transpose(), xj = X.row(j).transpose();
    E.row(i) = (xj - xi).transpose();
    B.row(i) = (0.5 * (xi + xj)).transpose();
    a += xi.cross(xj);
    c += xi;
  }
  a *= 0.5;
  c /= 4.0;
  r.area = a.norm();
  r.normal = a / r.area;
  Eigen::Matrix3d nx;
  nx << 0, -r.normal.z(), r.normal.y(), r.normal.z(), 0, -r.normal.x(), -r.normal.y(), r.normal.x(), 0;
  Eigen::Matrix<double, 3, 4> Bc = B.transpose();
  Bc.colwise() -= c;
  r.sharp = (nx * Bc) / r.area;
  r.flat = E * (Eigen::Matrix3d::Identity() - r.normal * r.normal.transpose());
  r.projection = Eigen::Matrix4d::Identity() - r.flat * r.sharp;
  r.inner_product = r.area * r.sharp.transpose() * r.sharp + lambda * r.projection.transpose() * r.projection;
  r.laplacian = -D.transpose() * r.inner_product * D;
  return r;
}

namespace {

const ParameterList& plain_parameters() {
  static const ParameterList list = {
      Parameter::real("lambda", 1.0, "stabilization weight of M1 (DGtal L0() uses 1)", "§2.2").at_least(0.0),
      extras_parameter()};
  return list;
}

const ParameterList& projected_parameters() {
  static const ParameterList list = ParameterList(plain_parameters()).append(normal_policy_parameters());
  return list;
}

class PolyDec final : public Discretization {
 public:
  explicit PolyDec(bool projected) : projected_(projected) {}
  std::string name() const override { return projected_ ? "projected-polydec" : "polydec"; }
  NormalKind required_normals() const override { return projected_ ? NormalKind::Face : NormalKind::None; }
  const ParameterList& parameters() const override { return projected_ ? projected_parameters() : plain_parameters(); }

  // Refills ops.L and ops.M in their existing storage (gather_quad_rows keeps the allocation).
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& config,
                     const QuadPattern* pattern, Operators& ops) const override {
    const std::string who = name();
    const ParameterValues params = parameters().read(config, who);
    const double lambda = params.real("lambda");
    const bool extras = params.boolean("extras");
    check_quad_mesh(mesh, who);

    reset_for_reuse(ops);
    Eigen::MatrixX3d u;
    if (projected_) u = prepare_normals(mesh, normals, NormalKind::Face, params, who, ops).matrix();
    const int F = mesh.num_faces();
    // Per face: L_f (16), |a_f| (1); with extras also U_f (12, column-major), V_f (12), M1_f (16).
    const std::size_t stride = extras ? 57 : 17;
    detail::PatternScratch data(pattern, std::size_t(F) * stride);  // pooled in the pattern: no page faults
    tbb::parallel_for(tbb::blocked_range<int>(0, F, 1024), [&](const tbb::blocked_range<int>& r) {
      for (int f = r.begin(); f != r.end(); ++f) {
        QuadCorners X = quad_corners(mesh, f);
        if (projected_) X = polydec_project_corners(X, u.row(f).transpose());
        const PolyDecLocal loc = polydec_local(X, lambda);
        double* d = data.data() + std::size_t(f) * stride;
        Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>{d} = loc.laplacian;
        d[16] = loc.area;
        if (extras) {
          Eigen::Map<QuadSharp>{d + 17} = loc.sharp;
          Eigen::Map<QuadFlat>{d + 29} = loc.flat;
          Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>{d + 41} = loc.inner_product;
        }
      }
    });
    const detail::VertexGather gather(mesh, pattern, who);
    const detail::VertexCorners& vc = gather.vc();
    detail::gather_quad_rows<1>(
        mesh, gather.pattern(), vc,
        [&](int f, int i, double* row) { std::copy_n(data.data() + std::size_t(f) * stride + 4 * i, 4, row); },
        {&ops.L});
    // docs/math.md §2.3: lumped mass M_vv = sum_f |a_f| / 4 (DGtal M0()).
    ops.M =
        detail::gather_corner_diagonal(mesh, vc, [&](int f, int) { return data[std::size_t(f) * stride + 16] / 4.0; });
    if (extras) {
      const EdgeTopology topo = build_edges(mesh);
      ops.M_lumped = ops.M;
      ops.D0 = global_d0(topo, mesh.num_vertices());
      std::vector<double> sharp(std::size_t(F) * 12), flat(std::size_t(F) * 12);
      for (int f = 0; f < F; ++f) {
        std::copy_n(data.data() + std::size_t(f) * stride + 17, 12, sharp.data() + std::size_t(f) * 12);
        std::copy_n(data.data() + std::size_t(f) * stride + 29, 12, flat.data() + std::size_t(f) * 12);
      }
      ops.sharp = global_sharp(topo, sharp.data());
      ops.flat = global_flat(topo, flat.data());
      // M1 assembled WITH the edge signs s_i s_j (docs/math.md §11 #13; DGtal's M1() omits them).
      ops.M1 = corrlap::assemble(quad_edge_plan(topo), [&](std::size_t b, std::size_t e, double* out) {
        for (std::size_t f = b; f < e; ++f, out += 16) std::copy_n(data.data() + f * stride + 41, 16, out);
      });
    }
  }

 private:
  bool projected_;
};

}  // namespace

std::unique_ptr<Discretization> make_polydec() { return std::make_unique<PolyDec>(false); }
std::unique_ptr<Discretization> make_projected_polydec() { return std::make_unique<PolyDec>(true); }

}  // namespace corrlap

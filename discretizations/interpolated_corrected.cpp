#include "interpolated_corrected.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/detail/interpolated_kernel.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace corrlap {

Eigen::Matrix4d interpolated_local_mass(double h, const Eigen::Vector4d& uz) {
  // 144 * int phi_g phi_l phi_k = a_s * a_t with a = 3 when the three hats share the parameter
  // value along that axis (m = 0 or 3 factors s), else 1: the 1D integrals of three linear hat
  // products are 1/4 and 1/12, hence 144 w in {9, 3, 1}.
  static const int alpha[4] = {0, 1, 1, 0}, beta[4] = {0, 0, 1, 1};
  auto w1 = [](int m) { return (m == 0 || m == 3) ? 3.0 : 1.0; };  // 12 * 1D integral
  const double q = h * h / 144.0;
  Eigen::Matrix4d M;
  for (int g = 0; g < 4; ++g)
    for (int l = g; l < 4; ++l) {
      double s = 0.0;
      for (int k = 0; k < 4; ++k) s += w1(alpha[g] + alpha[l] + alpha[k]) * w1(beta[g] + beta[l] + beta[k]) * uz[k];
      M(g, l) = M(l, g) = q * s;
    }
  return M;
}

namespace {
// a . b and a x b component by component: the order of the fast kernel
// (interpolated_corrected_fast.cpp), so that both give the same bits.
double dot3(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return a.x() * b.x() + a.y() * b.y() + a.z() * b.z();
}
Eigen::Vector3d cross3(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return {a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x()};
}
}  // namespace

InterpolatedLocal interpolated_local(const QuadCorners& x, const QuadCorners& u, double lambda, double kappa) {
  InterpolatedLocal r;
  // Edge vectors delta_i = x_{i+1} - x_i (docs/math.md §3.4).
  Eigen::Vector3d delta[4];
  for (int i = 0; i < 4; ++i) delta[i] = (x.row((i + 1) % 4) - x.row(i)).transpose();
  // Frame of docs/math.md §0: t1 = (x1-x0)/h, t2 = (x2-x1)/|x2-x1|, n = t1 x t2.
  const double h = std::sqrt(dot3(delta[0], delta[0]));
  const double inv_h = 1.0 / h;
  const Eigen::Vector3d t1 = delta[0] * inv_h;
  const Eigen::Vector3d t2 = delta[1] * (1.0 / std::sqrt(dot3(delta[1], delta[1])));
  const Eigen::Vector3d n = cross3(t1, t2);
  Eigen::Matrix3d R;
  R.col(0) = t1;
  R.col(1) = t2;
  R.col(2) = n;
  // Corner normals in frame components, ul(k, :) = (u_k.t1, u_k.t2, u_k.n), their edge-midpoint
  // and face averages (docs/math.md §3.1).
  Eigen::Matrix<double, 4, 3> ul, ue;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d uk = u.row(k).transpose();
    ul.row(k) << dot3(uk, t1), dot3(uk, t2), dot3(uk, n);
  }
  Eigen::Vector3d ub;
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 4; ++i) ue(i, c) = 0.5 * (ul(i, c) + ul((i + 1) % 4, c));
    ub[c] = 0.25 * (ul(0, c) + ul(1, c) + ul(2, c) + ul(3, c));
  }
  const double uz = ub.z();
  r.area = h * h * uz;
  r.ubar_z = uz;
  r.mass = interpolated_local_mass(h, ul.col(2));
  // docs/math.md §3.3 closed form S = S1 / 3 + S2 / 6, entry by entry (2 S1 + S2) / 6.
  constexpr double sixth = 1.0 / 6.0;
  r.S << (2.0 * uz + ue(0, 2)) * sixth, 0.0, -(2.0 * uz + ue(2, 2)) * sixth, 0.0,  //
      0.0, (2.0 * uz + ue(1, 2)) * sixth, 0.0, -(2.0 * uz + ue(3, 2)) * sixth,     //
      -(2.0 * ub.x() + ue(0, 0)) * sixth, -(2.0 * ub.y() + ue(1, 1)) * sixth, (2.0 * ub.x() + ue(2, 0)) * sixth,
      (2.0 * ub.y() + ue(3, 1)) * sixth;
  // G = S D (D of docs/math.md §0: (S D)(c, j) = S(c, j-1) - S(c, j)).
  Eigen::Matrix<double, 3, 4> G;
  for (int c = 0; c < 3; ++c)
    for (int j = 0; j < 4; ++j) G(c, j) = r.S(c, (j + 3) % 4) - r.S(c, j);
  // docs/math.md §3.5: a_f U^T U = S^T S / ubar^z, so D^T (a_f U^T U) D = G^T G / ubar^z.
  const double inv_uz = 1.0 / uz;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      r.sharp_stiffness(i, j) = (G(0, i) * G(0, j) + G(1, i) * G(1, j) + G(2, i) * G(2, j)) * inv_uz;
  r.sharp = R * r.S / (h * uz);
  // docs/math.md §3.4 flat with correction factor kappa: V_i = delta_i^T (I - kappa Q_i) with
  // Q_i = (2 u_a u_a^T + u_a u_b^T + u_b u_a^T + 2 u_b u_b^T) / 6, i.e.
  // V_i = delta_i - kappa/6 ((2 d_a + d_b) u_a + (d_a + 2 d_b) u_b), d_a = delta_i . u_a, d_b = delta_i . u_b.
  // P_f D = D - V U D = D - (V R) G / (h ubar^z) (docs/math.md §3.6a).
  const double w = inv_h * inv_uz, kk = kappa * sixth;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d ua = u.row(i).transpose(), ub_ = u.row((i + 1) % 4).transpose();
    const double da = dot3(delta[i], ua), db = dot3(delta[i], ub_);
    const double ca = kk * (2.0 * da + db), cb = kk * (da + 2.0 * db);
    const Eigen::Vector3d v(delta[i].x() - ca * ua.x() - cb * ub_.x(), delta[i].y() - ca * ua.y() - cb * ub_.y(),
                            delta[i].z() - ca * ua.z() - cb * ub_.z());
    r.flat.row(i) = v.transpose();
    const double vr0 = dot3(v, t1) * w, vr1 = dot3(v, t2) * w, vr2 = dot3(v, n) * w;
    for (int j = 0; j < 4; ++j) r.projected_difference(i, j) = -(vr0 * G(0, j) + vr1 * G(1, j) + vr2 * G(2, j));
    r.projected_difference(i, i) -= 1.0;
    r.projected_difference(i, (i + 1) % 4) += 1.0;
  }
  r.projection = Eigen::Matrix4d::Identity() - r.flat * r.sharp;
  r.inner_product = r.S.transpose() * r.S / uz + lambda * r.projection.transpose() * r.projection;
  // L_f = -D^T M_{1,f} D = -(G^T G / ubar^z + lambda (P_f D)^T (P_f D)).
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0.0;
      for (int m = 0; m < 4; ++m) s += r.projected_difference(m, i) * r.projected_difference(m, j);
      r.laplacian(i, j) = -(r.sharp_stiffness(i, j) + lambda * s);
    }
  return r;
}

namespace {

using RowMat4 = Eigen::Matrix<double, 4, 4, Eigen::RowMajor>;

class InterpolatedCorrected final : public Discretization {
 public:
  std::string name() const override { return "interpolated"; }
  NormalKind required_normals() const override { return NormalKind::Vertex; }
  const ParameterList& parameters() const override {
    static const ParameterList list =
        ParameterList{
            Parameter::real("lambda", 0.1, "stabilization weight of M1 (DGtal constructor default)", "§3.5")
                .at_least(0.0),
            Parameter::real("kappa", 2.0, "flat correction factor: 2 = DGtal, 1 = paper", "§3.4"),
            Parameter::choice("assembly", {"global", "local"},
                              "global (DGtal L0(), 2-ring stencil, §3.6a) | local (sum of L_f, §3.6b)", "§3.6"),
            extras_parameter()}
            .append(normal_policy_parameters());
    return list;
  }

  // Refills ops.L and ops.M in their existing storage (allocate_like and gather_quad_rows resize,
  // which keeps the allocation): the page faults of fresh output are a large part of a call
  // (bench/RESULTS.md, "bench_assembly", findings).
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& config,
                     const QuadPattern* pattern, Operators& ops) const override {
    const ParameterValues params = parameters().read(config, "interpolated");
    const double lambda = params.real("lambda");
    const double kappa = params.real("kappa");
    const bool global = params.choice("assembly") == "global";
    const bool extras = params.boolean("extras");
    check_quad_mesh(mesh, "interpolated");

    reset_for_reuse(ops);
    const PreparedNormals prepared = prepare_normals(mesh, normals, NormalKind::Vertex, params, "interpolated", ops);
    const Eigen::MatrixX3d& u = prepared.matrix();
    detail::interpolated_fast_assembly(mesh, u, pattern, lambda, kappa, global, ops);
    if (extras) add_extras(mesh, u, lambda, kappa, global, ops);
  }

 private:
  // D0, sharp, flat, M1 and the row-sum lumped M (docs/math.md §2.3, §3.6), from the reference local
  // operators (not a hot path).
  static void add_extras(const SurfelMesh& mesh, const Eigen::MatrixX3d& u, double lambda, double kappa, bool global,
                         Operators& ops) {
    const int F = mesh.num_faces();
    const EdgeTopology topo = build_edges(mesh);
    std::vector<double> sharp(std::size_t(F) * 12), flat(std::size_t(F) * 12), m1(std::size_t(F) * 16),
        areas(static_cast<std::size_t>(F));
    tbb::parallel_for(tbb::blocked_range<int>(0, F, 512), [&](const tbb::blocked_range<int>& r) {
      for (int f = r.begin(); f != r.end(); ++f) {
        const InterpolatedLocal loc =
            interpolated_local(quad_corners(mesh, f), quad_corner_rows(mesh, u, f), lambda, kappa);
        Eigen::Map<QuadSharp>{sharp.data() + std::size_t(f)* 12} = loc.sharp;
        Eigen::Map<QuadFlat>{flat.data() + std::size_t(f)* 12} = loc.flat;
        Eigen::Map<RowMat4>{m1.data() + std::size_t(f)* 16} = loc.inner_product;
        areas[std::size_t(f)] = loc.area;
      }
    });
    ops.M_lumped = row_sum_lumped(ops.M);  // docs/math.md §3.2: DGtal's lumpedM0() is not diagonal
    ops.D0 = global_d0(topo, mesh.num_vertices());
    ops.sharp = global_sharp(topo, sharp.data());
    ops.flat = global_flat(topo, flat.data());
    if (global) {
      Eigen::SparseMatrix<double> CA(3 * F, 3 * F);
      CA.reserve(Eigen::VectorXi::Constant(3 * F, 1));
      for (int f = 0; f < F; ++f)
        for (int c = 0; c < 3; ++c) CA.insert(3 * f + c, 3 * f + c) = areas[std::size_t(f)];
      Eigen::SparseMatrix<double> I(topo.num_edges(), topo.num_edges());
      I.setIdentity();
      const Eigen::SparseMatrix<double> P = I - Eigen::SparseMatrix<double>(*ops.flat * *ops.sharp);
      ops.M1 = Eigen::SparseMatrix<double>(ops.sharp->transpose() * CA * *ops.sharp) +
               lambda * Eigen::SparseMatrix<double>(P.transpose() * P);
    } else {
      ops.M1 = corrlap::assemble(quad_edge_plan(topo), [&](std::size_t b, std::size_t e, double* out) {
        for (std::size_t f = b; f < e; ++f, out += 16) std::copy_n(m1.data() + f * 16, 16, out);
      });
    }
  }
};

}  // namespace

std::unique_ptr<Discretization> make_interpolated_corrected() { return std::make_unique<InterpolatedCorrected>(); }

}  // namespace corrlap

#include "interpolated_corrected.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <memory>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <corrlap/core/error.hpp>

#include <corrlap/discretizations/detail/interpolated_kernel.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>
#include <corrlap/discretizations/assembly/detail/quad_pattern_access.hpp>

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
double dot3(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.x() * b.x() + a.y() * b.y() + a.z() * b.z(); }
Eigen::Vector3d cross3(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return {a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x()};
}
}  // namespace

InterpolatedLocal interpolated_local(const QuadCorners& x, const QuadCorners& u, double lambda, double kappa) {
  InterpolatedLocal r;
  // Edge vectors delta_i = x_{i+1} - x_i (spec §3.4).
  Eigen::Vector3d delta[4];
  for (int i = 0; i < 4; ++i) delta[i] = (x.row((i + 1) % 4) - x.row(i)).transpose();
  // Frame of spec §0: t1 = (x1-x0)/h, t2 = (x2-x1)/|x2-x1|, n = t1 x t2.
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
  // and face averages (spec §3.1).
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
  // spec §3.3 closed form S = S1 / 3 + S2 / 6, entry by entry (2 S1 + S2) / 6.
  constexpr double sixth = 1.0 / 6.0;
  r.S << (2.0 * uz + ue(0, 2)) * sixth, 0.0, -(2.0 * uz + ue(2, 2)) * sixth, 0.0,  //
      0.0, (2.0 * uz + ue(1, 2)) * sixth, 0.0, -(2.0 * uz + ue(3, 2)) * sixth,      //
      -(2.0 * ub.x() + ue(0, 0)) * sixth, -(2.0 * ub.y() + ue(1, 1)) * sixth, (2.0 * ub.x() + ue(2, 0)) * sixth,
      (2.0 * ub.y() + ue(3, 1)) * sixth;
  // G = S D (D of spec §0: (S D)(c, j) = S(c, j-1) - S(c, j)).
  Eigen::Matrix<double, 3, 4> G;
  for (int c = 0; c < 3; ++c)
    for (int j = 0; j < 4; ++j) G(c, j) = r.S(c, (j + 3) % 4) - r.S(c, j);
  // spec §3.5: a_f U^T U = S^T S / ubar^z, so D^T (a_f U^T U) D = G^T G / ubar^z.
  const double inv_uz = 1.0 / uz;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      r.sharp_stiffness(i, j) = (G(0, i) * G(0, j) + G(1, i) * G(1, j) + G(2, i) * G(2, j)) * inv_uz;
  r.sharp = R * r.S / (h * uz);
  // spec §3.4 flat with correction factor kappa: V_i = delta_i^T (I - kappa Q_i) with
  // Q_i = (2 u_a u_a^T + u_a u_b^T + u_b u_a^T + 2 u_b u_b^T) / 6, i.e.
  // V_i = delta_i - kappa/6 ((2 d_a + d_b) u_a + (d_a + 2 d_b) u_b), d_a = delta_i . u_a, d_b = delta_i . u_b.
  // P_f D = D - V U D = D - (V R) G / (h ubar^z) (spec §3.6a).
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

// Sized output with the given column structure (values uninitialized; the fill writes them all).
void allocate_like(Eigen::SparseMatrix<double>& A, int V, const int* outer) {
  detail::size_for_fill(A, V, outer[V]);
  std::copy(outer, outer + V + 1, A.outerIndexPtr());
}

// spec §3.6a: L = -D0^T (U^T C_A U + lambda P^T P) D0. Row e of P D0 is
// r_e = (1/n_e) sum_{f ni e} s_{f,i} (P_f D)[i, :] on the vertices of f, so
// L = -sum_f D^T (S^T S / ubar^z) D - lambda sum_e r_e r_e^T. Assembled by vertex columns: column v
// sums the face terms of its faces (incidences ascending) and then lambda r_e[v] r_e over the
// edges of its faces (ascending), so the result is the same for any thread count.
// `faceterms` holds the per-face records of interpolated_face_range; `r` the edge rows (k per edge).
// When `mpat` is given, M (spec §3.2, M = sum_f M0_f) is filled in the same column pass, with the
// same summation order as detail::gather_quad_rows.
template <class Pos>
void fill_columns(const detail::ProjectionPattern& pp, const detail::VertexCorners& vc, const detail::QuadVertexPattern* mpat,
                  const double* faceterms, const double* r, double lambda, const Pos* face_pos, const Pos* ce_pos,
                  Eigen::SparseMatrix<double>& L, Eigen::SparseMatrix<double>* M) {
  const int V = int(vc.start.size()) - 1, k = pp.k;
  const int* outer = pp.outer.data();
  const int* pin = pp.inner.data();
  int* inner = L.innerIndexPtr();
  double* val = L.valuePtr();
  const int* vstart = vc.start.data();
  const int* vcorner = vc.corner.data();
  const int* ce_start = pp.ce_start.data();
  const int* ce_edge = pp.ce_edge.data();
  const std::uint8_t* ce_sv = pp.ce_sv.data();
  const std::uint8_t* esize = pp.size.data();
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 1024), [&](const tbb::blocked_range<int>& range) {
    // Rows and zeroed values of the whole block first (sequential streams), then accumulation.
    const std::size_t b = std::size_t(outer[range.begin()]), e = std::size_t(outer[range.end()]);
    std::copy(pin + b, pin + e, inner + b);
    std::fill(val + b, val + e, 0.0);
    const int* mouter = nullptr;
    double* mval = nullptr;
    const std::uint16_t* mslot = nullptr;
    if (M) {
      mouter = mpat->outer.data();
      mval = M->valuePtr();
      mslot = mpat->slot.data();
      const std::size_t mb = std::size_t(mouter[range.begin()]), me = std::size_t(mouter[range.end()]);
      std::copy(mpat->inner.data() + mb, mpat->inner.data() + me, M->innerIndexPtr() + mb);
      std::fill(mval + mb, mval + me, 0.0);
    }
    constexpr int ahead = 2;  // columns: the edge rows and face records are scattered in memory
    for (int v = range.begin(); v != range.end(); ++v) {
      if (v + ahead < V) {
        for (int q = ce_start[v + ahead]; q < ce_start[v + ahead + 1]; ++q)
          __builtin_prefetch(r + std::size_t(ce_edge[q]) * std::size_t(k));
        for (int a = vstart[v + ahead]; a < vstart[v + ahead + 1]; ++a)
          __builtin_prefetch(faceterms + std::size_t(vcorner[a] >> 2) * detail::kTermsStride);
      }
      double* col = val + outer[v];
      double* mcol = M ? mval + mouter[v] : nullptr;
      for (int a = vstart[v]; a < vstart[v + 1]; ++a) {
        const int c = vcorner[a];
        const double* t = faceterms + std::size_t(c >> 2) * detail::kTermsStride;
        const int i = c & 3;
        const Pos* fp = face_pos + 4 * std::size_t(a);
        for (int j = 0; j < 4; ++j) col[fp[j]] -= t[detail::kTermsK1 + detail::kSym[i][j]];
        if (mcol) {
          double row[4];
          detail::interpolated_mass_row(t, i, row);
          const std::uint16_t* ms = mslot + 4 * std::size_t(a);
          for (int j = 0; j < 4; ++j) mcol[ms[j]] += row[j];
        }
      }
      for (int q = ce_start[v]; q < ce_start[v + 1]; ++q) {
        const std::size_t ed = std::size_t(ce_edge[q]);
        const double* re = r + ed * std::size_t(k);
        const double a = lambda * re[ce_sv[q]];
        if (a == 0.0) continue;
        const Pos* cp = ce_pos + std::size_t(q) * std::size_t(k);
        const int n = esize[ed];
        for (int s = 0; s < n; ++s) col[cp[s]] -= a * re[s];
      }
    }
  });
}

// Rows r_e of P D0 (spec §3.6a), one per edge, on the element slots: sum over the incidences in
// face order of s_{f,i} / n_e (P_f D)[i, :]. `pd` holds P_f D per face (row-major 4x4).
// The second face of an edge is often far from the first in face order (spec §1.4 sorts by
// orientation first), so its row is a cache miss: prefetching 16 edges ahead took the pass from
// 32 to 24 ms at h = 0.005 (one thread).
void edge_rows(const detail::ProjectionPattern& pp, const double* pd, double* r) {
  const int k = pp.k, E = pp.num_edges;
  const int* inc_start = pp.inc_start.data();
  const int* inc_row = pp.inc_row.data();
  const double* inc_coef = pp.inc_coef.data();
  const std::uint8_t* inc_slot = pp.inc_slot.data();
  const std::uint8_t* size = pp.size.data();
  tbb::parallel_for(tbb::blocked_range<int>(0, E, 4096), [&](const tbb::blocked_range<int>& range) {
    constexpr int ahead = 16;
    for (int e = range.begin(); e != range.end(); ++e) {
      if (e + ahead < E)
        for (int a = inc_start[e + ahead]; a < inc_start[e + ahead + 1]; ++a)
          __builtin_prefetch(pd + 4 * std::size_t(inc_row[a]));
      double* re = r + std::size_t(e) * std::size_t(k);
      for (int s = 0; s < size[e]; ++s) re[s] = 0.0;
      for (int a = inc_start[e]; a < inc_start[e + 1]; ++a) {
        const double* row = pd + 4 * std::size_t(inc_row[a]);
        const std::uint8_t* slot = inc_slot + 4 * std::size_t(a);
        const double coef = inc_coef[a];
        for (int j = 0; j < 4; ++j) re[slot[j]] += coef * row[j];
      }
    }
  });
}

class InterpolatedCorrected final : public Discretization {
 public:
  std::string name() const override { return "interpolated"; }
  NormalKind required_normals() const override { return NormalKind::Vertex; }
  std::vector<ParameterInfo> parameters() const override {
    std::vector<ParameterInfo> p = {
        {"lambda", "0.1", "stabilization weight of M1 (spec §3.5; DGtal constructor default)"},
        {"kappa", "2", "flat correction factor (spec §3.4): 2 = DGtal, 1 = paper"},
        {"assembly", "global", "global (spec §3.6a, DGtal L0(), 2-ring stencil) | local (§3.6b, sum of L_f)"},
        extras_parameter()};
    for (auto& q : normal_policy_parameters()) p.push_back(q);
    return p;
  }

  Operators assemble(const SurfelMesh& mesh, const NormalFields& normals, const Config& params) const override {
    Operators ops;
    assemble_into(mesh, normals, params, nullptr, ops);
    return ops;
  }

  // Refills ops.L and ops.M in their existing storage (allocate_like and gather_quad_rows resize,
  // which keeps the allocation): on a VM the page faults of fresh output were ~130 ms of the
  // ~350 ms per call at h = 0.005.
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& params,
                     const QuadPattern* pattern, Operators& ops) const override {
    params.check_parameters(parameters(), "interpolated parameters");
    const double lambda = params.get_double("lambda", 0.1);
    const double kappa = params.get_double("kappa", 2.0);
    if (!(std::isfinite(lambda) && lambda >= 0.0)) throw InputError("interpolated: lambda must be finite and >= 0");
    if (!std::isfinite(kappa)) throw InputError("interpolated: kappa must be finite");
    const std::string assembly = params.get_string("assembly", "global");
    if (assembly != "global" && assembly != "local")
      throw InputError("interpolated: assembly '" + assembly + "': expected global or local");
    const bool global = assembly == "global";
    const bool extras = params.get_bool("extras", false);
    check_quad_mesh(mesh, "interpolated");

    reset_for_reuse(ops);
    const PreparedNormals prepared =
        prepare_normals(mesh, normals, NormalKind::Vertex, params, "interpolated", ops.warnings);
    const Eigen::MatrixX3d& u = prepared.matrix();
    const int F = mesh.num_faces();
    const detail::VertexGather gather(mesh, pattern, "interpolated");
    const detail::QuadVertexPattern* pat = gather.pattern();
    const detail::VertexCorners& vc = gather.vc();
    // The projection structure (spec §3.6a): the pattern's (built on its first use), else built
    // for this assembly.
    std::unique_ptr<detail::ProjectionPattern> own_pp;
    const detail::ProjectionPattern* pp = nullptr;
    if (global) {
      if (pattern) pp = &detail::projection_pattern(*pattern);
      else pp = (own_pp = detail::build_projection_pattern(mesh.faces.data(), F, vc)).get();
    }
    // One reused buffer (no first-touch page faults in steady state; every read entry is
    // written first): the face records of interpolated_face_range (local assembly: L_f packed in
    // place of K1), P_f D per face, then the edge rows r_e (k per edge, global).
    const std::size_t pd_off = std::size_t(F) * detail::kTermsStride, r_off = pd_off + std::size_t(F) * 16;
    detail::PatternScratch data(pattern, r_off + (global ? std::size_t(pp->num_edges) * std::size_t(pp->k) : 0));
    double* terms = data.data();
    double* pdata = data.data() + pd_off;
    const double* px = mesh.positions.col(0).data();
    const double* py = mesh.positions.col(1).data();
    const double* pz = mesh.positions.col(2).data();
    const int* faces = mesh.faces.data();
    std::atomic<int> non_square{-1};
    const double* const xc[3] = {px, py, pz};
    const double* const uc[3] = {u.col(0).data(), u.col(1).data(), u.col(2).data()};
    tbb::parallel_for(tbb::blocked_range<int>(0, F, 1024), [&](const tbb::blocked_range<int>& r) {
      // The closed forms of spec §3.2-§3.4 hold on surfels (squares); other quads are rejected.
      const int bad = detail::interpolated_face_range(faces, r.begin(), r.end(), xc, uc, kappa, terms, pdata);
      if (bad >= 0) {
        int cur = non_square.load();
        while ((cur < 0 || bad < cur) && !non_square.compare_exchange_weak(cur, bad)) {}
        return;
      }
      if (!global)
        for (int f = r.begin(); f != r.end(); ++f) {
          // L_f = -D^T M1 D = -(K1 + lambda (P D)^T (P D)) (spec §3.5), packed like K1.
          double* t = terms + std::size_t(f) * detail::kTermsStride;
          const double* pd = pdata + std::size_t(f) * 16;
          for (int i = 0; i < 4; ++i)
            for (int j = i; j < 4; ++j) {
              double s = 0.0;
              for (int m = 0; m < 4; ++m) s += pd[4 * m + i] * pd[4 * m + j];
              double& k = t[detail::kTermsK1 + detail::kSym[i][j]];
              k = -(k + lambda * s);
            }
        }
    });
    if (non_square.load() >= 0)
      throw InputError("interpolated: face " + std::to_string(non_square.load()) +
                       " is not a square; the interpolated corrected calculus needs a mesh of surfels (spec §3)");
    if (global) {
      double* r = data.data() + r_off;
      edge_rows(*pp, pdata, r);
      allocate_like(ops.L, mesh.num_vertices(), pp->outer.data());
      if (pat) allocate_like(ops.M, mesh.num_vertices(), pat->outer.data());
      else
        detail::gather_quad_rows<1>(
            mesh, nullptr, vc,
            [&](int f, int i, double* row) { detail::interpolated_mass_row(terms + std::size_t(f) * detail::kTermsStride, i, row); },
            {&ops.M});
      Eigen::SparseMatrix<double>* M = pat ? &ops.M : nullptr;
      if (pp->wide)
        fill_columns<int>(*pp, vc, pat, terms, r, lambda, pp->face_pos32.data(), pp->ce_pos32.data(), ops.L, M);
      else
        fill_columns<std::uint8_t>(*pp, vc, pat, terms, r, lambda, pp->face_pos8.data(), pp->ce_pos8.data(), ops.L, M);
    } else {
      detail::gather_quad_rows<2>(
          mesh, pat, vc,
          [&](int f, int i, double* rows) {
            const double* t = terms + std::size_t(f) * detail::kTermsStride;
            detail::interpolated_mass_row(t, i, rows);
            for (int j = 0; j < 4; ++j) rows[4 + j] = t[detail::kTermsK1 + detail::kSym[i][j]];
          },
          {&ops.M, &ops.L});
    }
    if (extras) add_extras(mesh, u, lambda, kappa, global, ops);
  }

 private:
  // D0, sharp, flat, M1 and the row-sum lumped M (spec §2.3, §3.6), from the reference local
  // operators (not a hot path).
  static void add_extras(const SurfelMesh& mesh, const Eigen::MatrixX3d& u, double lambda, double kappa, bool global,
                         Operators& ops) {
    const int F = mesh.num_faces();
    const EdgeTopology topo = build_edges(mesh);
    std::vector<double> sharp(std::size_t(F) * 12), flat(std::size_t(F) * 12), m1(std::size_t(F) * 16), areas(static_cast<std::size_t>(F));
    tbb::parallel_for(tbb::blocked_range<int>(0, F, 512), [&](const tbb::blocked_range<int>& r) {
      for (int f = r.begin(); f != r.end(); ++f) {
        const InterpolatedLocal loc = interpolated_local(quad_corners(mesh, f), quad_corner_rows(mesh, u, f), lambda, kappa);
        Eigen::Map<QuadSharp>{sharp.data() + std::size_t(f) * 12} = loc.sharp;
        Eigen::Map<QuadFlat>{flat.data() + std::size_t(f) * 12} = loc.flat;
        Eigen::Map<RowMat4>{m1.data() + std::size_t(f) * 16} = loc.inner_product;
        areas[std::size_t(f)] = loc.area;
      }
    });
    ops.M_lumped = row_sum_lumped(ops.M);  // spec §3.2: DGtal's lumpedM0() is not diagonal
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

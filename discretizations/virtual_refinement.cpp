#include "virtual_refinement.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/QR>
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/assembly/detail/quad_pattern_access.hpp>
#include <corrlap/discretizations/assembly/parallel_assembly.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>
#include <memory>
#include <sstream>
#include <vector>

#include "quad_assembly.hpp"

namespace corrlap {

namespace {

// K_f = P^T K_fan P with P = [I_4; w^T] (refined index 4 = virtual point), docs/math.md §5.1 step 5.
Eigen::Matrix4d restrict_fan(const Eigen::Matrix<double, 5, 5>& F, const Eigen::Vector4d& w) {
  Eigen::Matrix4d R;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) R(a, b) = F(a, b) + w[b] * F(a, 4) + w[a] * F(4, b) + w[a] * w[b] * F(4, 4);
  return R;
}

Eigen::Matrix4d row_sum_lump(const Eigen::Matrix4d& M) { return M.rowwise().sum().asDiagonal(); }

Eigen::Vector4d bilinear_basis(double s, double t) { return {(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t}; }

}  // namespace

// ---------------------------------------------------------------------- uncorrected VRM

Eigen::Vector4d vrm_virtual_weights(const QuadPositions& Xin) {
  // docs/math.md §5.1 step 1: A_ij = sum_k (x_j x d_k).(x_i x d_k), b_i = sum_k (x_i x d_k).(x_k x d_k),
  // plus the row sum_j w_j = 1, solved by complete orthogonal decomposition (least squares,
  // minimum norm), as pmp does. Centring keeps the entries O(h^4) instead of O(|x|^2 h^2).
  const Eigen::RowVector3d c = Xin.colwise().mean();
  QuadPositions X = Xin.rowwise() - c;
  Eigen::Matrix<double, 5, 4> A = Eigen::Matrix<double, 5, 4>::Zero();
  Eigen::Matrix<double, 5, 1> b = Eigen::Matrix<double, 5, 1>::Zero();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d dk = (X.row((k + 1) % 4) - X.row(k)).transpose();
    Eigen::Vector3d cr[4];
    for (int j = 0; j < 4; ++j) cr[j] = X.row(j).transpose().cross(dk);
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) A(i, j) += cr[j].dot(cr[i]);
      b[i] += cr[i].dot(cr[k]);
    }
  }
  A.row(4).setOnes();
  b[4] = 1.0;
  // Scale the geometric rows to O(1) so the rank decision of the decomposition is relative.
  const double scale = A.topRows<4>().cwiseAbs().maxCoeff();
  if (scale > 0.0) {
    A.topRows<4>() /= scale;
    b.head<4>() /= scale;
  }
  Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<double, 5, 4>> cod(A);
  cod.setThreshold(1e-10);
  return cod.solve(b);
}

VrmLocal vrm_local(const QuadPositions& X) {
  VrmLocal out;
  out.w = vrm_virtual_weights(X);
  const Eigen::Vector3d p = X.transpose() * out.w;
  Eigen::Matrix<double, 5, 5> Kfan = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> mfan = Eigen::Matrix<double, 5, 1>::Zero();
  for (int i = 0; i < 4; ++i) {
    const int id[3] = {i, (i + 1) % 4, 4};
    const Eigen::Vector3d y0 = X.row(i).transpose(), y1 = X.row((i + 1) % 4).transpose();
    Eigen::Matrix3d Kt;
    if (!cotan_triangle_stiffness((p - y1).norm(), (p - y0).norm(), (y1 - y0).norm(), Kt)) {
      ++out.skipped_triangles;
      continue;
    }
    const Eigen::Vector3d m = mixed_voronoi_triangle_mass(y0, y1, p);
    for (int a = 0; a < 3; ++a) {
      mfan[id[a]] += m[a];
      for (int b = 0; b < 3; ++b) Kfan(id[a], id[b]) += Kt(a, b);
    }
  }
  out.K = restrict_fan(Kfan, out.w);
  // M_f = diag(row sums of P^T M_fan P) (docs/math.md §5.1 step 5)
  out.M = row_sum_lump(restrict_fan(Eigen::Matrix<double, 5, 5>(mfan.asDiagonal()), out.w));
  return out;
}

// ------------------------------------------------------------------------- corrected VRM

Eigen::Vector4d corrected_fan_areas(const Eigen::Vector4d& uz, double s, double t,
                                    Eigen::Matrix<double, 4, 2>* gradient, Eigen::Matrix2d* hessians) {
  // docs/math.md §5.2: U(s,t) = a + b s + c t + d s t (bilinear interpolation of uz). Triangle T_i =
  // (q_i, q_{i+1}, p); its integral of U is |T_i|/3 times the sum of U at the three side midpoints
  // (exact for degree <= 2). |T_i| = cross(q_{i+1} - q_i, p - q_i)/2 is affine in p.
  static const double q[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const double a = uz[0], b = uz[1] - uz[0], c = uz[3] - uz[0], d = uz[0] - uz[1] + uz[2] - uz[3];
  auto U = [&](double x, double y) { return a + b * x + c * y + d * x * y; };
  Eigen::Vector4d A;
  for (int i = 0; i < 4; ++i) {
    const double* q0 = q[i];
    const double* q1 = q[(i + 1) % 4];
    const double ex = q1[0] - q0[0], ey = q1[1] - q0[1];
    const double area = 0.5 * (ex * (t - q0[1]) - ey * (s - q0[0]));
    const double mb[2] = {0.5 * (q1[0] + s), 0.5 * (q1[1] + t)};
    const double mc[2] = {0.5 * (q0[0] + s), 0.5 * (q0[1] + t)};
    const double S = U(0.5 * (q0[0] + q1[0]), 0.5 * (q0[1] + q1[1])) + U(mb[0], mb[1]) + U(mc[0], mc[1]);
    A[i] = area * S / 3.0;
    if (gradient || hessians) {
      const Eigen::Vector2d ga(-0.5 * ey, 0.5 * ex);
      // grad S = (grad U(mb) + grad U(mc)) / 2, grad U(x, y) = (b + d y, c + d x)
      const Eigen::Vector2d gs(0.5 * (2 * b + d * (mb[1] + mc[1])), 0.5 * (2 * c + d * (mb[0] + mc[0])));
      if (gradient) gradient->row(i) = ((ga * S + area * gs) / 3.0).transpose();
      if (hessians) {
        Eigen::Matrix2d HS;
        HS << 0, 0.5 * d, 0.5 * d, 0;
        hessians[i] = (ga * gs.transpose() + gs * ga.transpose() + area * HS) / 3.0;
      }
    }
  }
  return A;
}

double corrected_fan_energy(const Eigen::Vector4d& uz, double s, double t, Eigen::Vector2d* gradient,
                            Eigen::Matrix2d* hessian) {
  Eigen::Matrix<double, 4, 2> G;
  Eigen::Matrix2d H[4];
  const bool derivs = gradient || hessian;
  const Eigen::Vector4d A = corrected_fan_areas(uz, s, t, derivs ? &G : nullptr, hessian ? H : nullptr);
  if (gradient) *gradient = 2.0 * G.transpose() * A;
  if (hessian) {
    hessian->setZero();
    for (int i = 0; i < 4; ++i) *hessian += 2.0 * (G.row(i).transpose() * G.row(i) + A[i] * H[i]);
  }
  return A.squaredNorm();
}

VirtualPoint minimize_virtual_point(const Eigen::Vector4d& uz, const VirtualPointOptions& opt) {
  const double lo = opt.clamp, hi = 1.0 - opt.clamp;
  VirtualPoint vp;
  double s = 0.5, t = 0.5;
  Eigen::Vector2d g;
  Eigen::Matrix2d H;
  double E = corrected_fan_energy(uz, s, t, &g, &H);
  const double ubar = uz.mean();
  const double gstep = std::abs(ubar) > 1e-3 ? 1.0 / (ubar * ubar) : 1e6;
  // Gradient projected on the box: a component pushing outward at an active bound is dropped.
  auto projected = [&](const Eigen::Vector2d& grad) {
    Eigen::Vector2d pg = grad;
    const double x[2] = {s, t};
    for (int k = 0; k < 2; ++k)
      if ((x[k] <= lo && grad[k] > 0) || (x[k] >= hi && grad[k] < 0)) pg[k] = 0;
    return pg;
  };
  bool stationary = false;
  int it = 0;
  for (; it < opt.max_iterations; ++it) {
    if (projected(g).norm() < opt.gradient_tolerance) break;
    Eigen::Vector2d dir;
    const double det = H.determinant();
    bool newton = H(0, 0) > 0 && det > 0;
    if (newton) {
      dir = -H.inverse() * g;  // docs/math.md §5.2: Newton with the analytic Hessian
    } else {
      dir = -gstep * g;  // fallback: gradient step 1/ubar^2
    }
    if (dir.dot(g) >= 0) {
      dir = -gstep * g;
      newton = false;
    }
    double alpha = 1.0;
    bool accepted = false;
    double s1 = s, t1 = t, E1 = E;
    Eigen::Vector2d g1;
    for (int bt = 0; bt < 60; ++bt, alpha *= 0.5) {  // backtracking
      s1 = std::clamp(s + alpha * dir[0], lo, hi);
      t1 = std::clamp(t + alpha * dir[1], lo, hi);
      if (s1 == s && t1 == t) break;
      E1 = corrected_fan_energy(uz, s1, t1, &g1);
      if (E1 < E) {
        accepted = true;
        break;
      }
      // Near the minimum the decrease of E (~|g|^2/|H|) falls below the resolution of E while
      // |g| is still ~1e-9: accept a full Newton step that keeps E within round-off and reduces
      // the gradient, so Newton's quadratic convergence reaches the 1e-12 tolerance.
      if (newton && bt == 0 && E1 <= E * (1.0 + 8.0 * DBL_EPSILON) && g1.norm() < 0.5 * g.norm()) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {  // no representable decrease: stationary up to round-off
      stationary = true;
      break;
    }
    s = s1;
    t = t1;
    E = corrected_fan_energy(uz, s, t, &g, &H);
  }
  const double pg = projected(g).norm();
  vp.s = s;
  vp.t = t;
  vp.iterations = it;
  vp.energy = E;
  vp.gradient_norm = pg;
  vp.converged = std::isfinite(E) && (pg < opt.gradient_tolerance || (stationary && pg < 1e-9));
  return vp;
}

CorrectedVrmLocal corrected_vrm_local(const QuadPositions& X, const QuadPositions& U, const Eigen::Vector3d& n,
                                      bool lumped_mass, const VirtualPointOptions& options) {
  CorrectedVrmLocal out;
  Eigen::Vector4d uz;
  for (int k = 0; k < 4; ++k) uz[k] = U.row(k).dot(n);
  // Parametric Jacobian of the bilinear quad: h^2 on a surfel (docs/math.md §5.2, A_i = h^2 iint_{T_i} U).
  const double J = (X.row(1) - X.row(0)).cross(X.row(3) - X.row(0)).norm();
  out.point = minimize_virtual_point(uz, options);
  out.w = bilinear_basis(out.point.s, out.point.t);
  out.areas = J * corrected_fan_areas(uz, out.point.s, out.point.t);
  const Eigen::Vector3d p = X.transpose() * out.w;
  const Eigen::Vector3d up = U.transpose() * out.w;
  Eigen::Matrix<double, 5, 5> Kfan = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 5> Mfan = Eigen::Matrix<double, 5, 5>::Zero();
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    const int id[3] = {i, j, 4};
    const Eigen::Vector3d y0 = X.row(i).transpose(), y1 = X.row(j).transpose();
    // triangle normal (choice, docs/math.md §5.2): normalize(u_i + u_{i+1} + u_p)
    Eigen::Vector3d uT = U.row(i).transpose() + U.row(j).transpose() + up;
    const double un = uT.norm();
    // lumped barycentric triangle mass with the integral area A_i (docs/math.md §5.2)
    for (int a = 0; a < 3; ++a) Mfan(id[a], id[a]) += out.areas[i] / 3.0;
    Eigen::Matrix3d Kt;
    if (!(un > 0.0) || !cotan_triangle_stiffness((p - y1).cross(uT / un).norm(), (p - y0).cross(uT / un).norm(),
                                                 (y1 - y0).cross(uT / un).norm(), Kt)) {
      ++out.skipped_triangles;
      continue;
    }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) Kfan(id[a], id[b]) += Kt(a, b);
  }
  out.K = restrict_fan(Kfan, out.w);
  out.M = restrict_fan(Mfan, out.w);
  if (lumped_mass) out.M = row_sum_lump(out.M);
  return out;
}

// ------------------------------------------------------------------------- discretizations

namespace {

QuadPositions corners_of(const SurfelMesh& mesh, int f) {
  QuadPositions X;
  for (int k = 0; k < 4; ++k) X.row(k) = mesh.positions.row(mesh.faces(f, k));
  return X;
}

class Vrm final : public Discretization {
 public:
  explicit Vrm(bool corrected) : corrected_(corrected) {}
  std::string name() const override { return corrected_ ? "corrected-vrm" : "vrm"; }
  NormalKind required_normals() const override { return corrected_ ? NormalKind::Vertex : NormalKind::None; }
  const ParameterList& parameters() const override {
    static const ParameterList none;
    static const ParameterList corrected =
        ParameterList{
            Parameter::choice("mass", {"full", "lumped"}, "full: M_f = P^T M_fan P (4x4) | lumped: its row sums",
                              "§5.2"),
            Parameter::integer("max_iterations", 50, "virtual-point minimizer: iteration limit", "§5.2").at_least(1),
            Parameter::real("gradient_tolerance", 1e-12, "virtual-point minimizer: stop when |grad E/h^4| is below",
                            "§5.2")
                .above(0.0)}
            .append(normal_policy_parameters());
    return corrected_ ? corrected : none;
  }

  // Refills ops.L and ops.M in their existing storage (gather_quad_rows keeps the allocation).
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& config,
                     const QuadPattern* pattern, Operators& ops) const override {
    const ParameterValues params = parameters().read(config, name());
    validate_mesh(mesh, name().c_str());
    reset_for_reuse(ops);
    const int F = mesh.num_faces();
    if (F == 0) throw InputError(name() + ": the mesh has no face");

    bool lumped_mass = false;
    VirtualPointOptions vopt;
    Eigen::MatrixX3d u, n;
    std::string policy;
    if (corrected_) {
      lumped_mass = params.choice("mass") == "lumped";
      vopt.max_iterations = params.integer("max_iterations");
      vopt.gradient_tolerance = params.real("gradient_tolerance");
      policy = params.choice("orientation");
      u = prepare_normals(mesh, normals, NormalKind::Vertex, params, name(), ops).matrix();
      n = trivial_face_normals(mesh);  // docs/math.md §1.3/§1.5: outward trivial normal
    }

    // Per face: K_f (16 values, row-major) then M_f: its diagonal (4 values) when the mass is
    // lumped (vrm always, docs/math.md §5.1 step 5), else the full 4x4. Not zero-filled: the parallel
    // kernel loop writes every value, so the first-touch page faults are spread over the threads
    // (huge pages where possible). Not pooled either (unlike fem's small per-face scratch): the
    // kernels dominate here, and a pooled 20-32 doubles per face would stay resident.
    const bool full_mass = corrected_ && !lumped_mass;
    const std::size_t S = full_mass ? 32 : 20;
    const std::unique_ptr<double[]> loc = detail::fresh_buffer(std::size_t(F) * S);
    // Rare events (skipped fan triangles, minimizer failures) collected per thread and merged in
    // face order below: no per-face report arrays.
    struct Report {
      long long skipped = 0;
      int first_skip = -1;
      std::vector<std::pair<int, VirtualPoint>> failed;
    };
    tbb::enumerable_thread_specific<Report> reports;

    // One parallel pass computes both local matrices of each face (no per-face allocation).
    tbb::parallel_for(tbb::blocked_range<int>(0, F, 512), [&](const tbb::blocked_range<int>& r) {
      Report& rep = reports.local();
      for (int f = r.begin(); f != r.end(); ++f) {
        const QuadPositions X = corners_of(mesh, f);
        double* out = loc.get() + std::size_t(f) * S;
        Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>> K(out);
        int skipped = 0;
        if (corrected_) {
          QuadPositions Uf;
          for (int k = 0; k < 4; ++k) Uf.row(k) = u.row(mesh.faces(f, k));
          const CorrectedVrmLocal l = corrected_vrm_local(X, Uf, n.row(f).transpose(), lumped_mass, vopt);
          K = l.K;
          if (full_mass)
            Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(out + 16) = l.M;
          else
            for (int k = 0; k < 4; ++k) out[16 + k] = l.M(k, k);
          skipped = l.skipped_triangles;
          if (!l.point.converged) rep.failed.emplace_back(f, l.point);
        } else {
          const VrmLocal l = vrm_local(X);
          K = l.K;
          for (int k = 0; k < 4; ++k) out[16 + k] = l.M(k, k);
          skipped = l.skipped_triangles;
        }
        if (skipped) {
          rep.skipped += skipped;
          if (rep.first_skip < 0 || f < rep.first_skip) rep.first_skip = f;
        }
      }
    });

    // Vertex-row gather through the per-connectivity pattern (quad_row_gather.hpp): every entry is
    // the sum of its face contributions in ascending face order, from +0.0 -- the order of the
    // generic AssemblyPlan this replaces, so the bits are unchanged -- and is written once.
    // Local matrices are not bitwise symmetric (P^T K P), so the kernel hands columns.
    const detail::VertexGather gather(mesh, pattern, name());
    const detail::QuadVertexPattern* pat = gather.pattern();
    const detail::VertexCorners& vc = gather.vc();
    const double* lp = loc.get();
    // docs/math.md §5.1 step 6: L = -sum K_f (negative semi-definite); negating each finished column gives
    // the bits of negating the finished matrix.
    auto negate_L = [](int, const auto& col, int len) {
      for (int t = 0; t < len; ++t) col[0][t] *= -1.0;
    };
    if (full_mass) {
      auto columns = [&](int f, int i, double* c) {
        const double* o = lp + std::size_t(f) * S;
        for (int j = 0; j < 4; ++j) c[j] = o[4 * j + i], c[4 + j] = o[16 + 4 * j + i];
      };
      detail::gather_quad_rows<2>(mesh, pat, vc, columns, {&ops.L, &ops.M}, negate_L);
      // Row sums of the assembled M, bitwise as a sequential scan (the lumped alternative).
      ops.M_lumped = detail::row_sum_diagonal_symmetric(ops.M);
    } else {
      auto columns = [&](int f, int i, double* c) {
        const double* o = lp + std::size_t(f) * S;
        for (int j = 0; j < 4; ++j) c[j] = o[4 * j + i];
      };
      detail::gather_quad_rows<1>(mesh, pat, vc, columns, {&ops.L}, negate_L);
      // Diagonal local masses: the assembled M is diagonal, entry v = sum over the corners at v in
      // ascending face order (what summing the assembled zeros of the off-diagonal gives, bit for bit).
      ops.M = detail::gather_corner_diagonal(
          mesh, vc, [&](int f, int i) { return lp[std::size_t(f) * S + 16 + std::size_t(i)]; });
    }

    // Merge the per-thread reports in face order.
    long long nskip = 0;
    int first_skip = -1;
    std::vector<std::pair<int, VirtualPoint>> failed;
    for (const Report& rep : reports) {
      nskip += rep.skipped;
      if (rep.first_skip >= 0 && (first_skip < 0 || rep.first_skip < first_skip)) first_skip = rep.first_skip;
      failed.insert(failed.end(), rep.failed.begin(), rep.failed.end());
    }
    std::sort(failed.begin(), failed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });

    // Reports, in face order (deterministic).
    if (nskip > 0) {
      std::ostringstream os;
      os << name() << ": " << nskip << " degenerate fan triangle(s) (zero " << (corrected_ ? "corrected " : "")
         << "area) skipped, first in face " << first_skip;
      if (policy == "error") throw InputError(os.str());
      ops.warnings.push_back(os.str());
    }
    if (corrected_) {
      int bad = 0, worst = -1;
      double worst_g = -1;
      const VirtualPoint* worst_point = nullptr;
      for (const auto& [f, vp] : failed) {
        ++bad;
        if (!(vp.gradient_norm <= worst_g)) {
          worst_g = vp.gradient_norm;
          worst = f;
          worst_point = &vp;
        }
      }
      if (bad > 0) {
        std::ostringstream os;
        os.precision(3);
        os << name() << ": the virtual-point minimizer did not converge on " << bad << " of " << F
           << " faces (worst: face " << worst << ", |grad E/h^4| = " << worst_g << ", (s0, t0) = (" << worst_point->s
           << ", " << worst_point->t << "))";
        if (policy == "error") throw NumericalError(os.str());
        ops.warnings.push_back(os.str());
      }
    }
  }

 private:
  bool corrected_;
};

}  // namespace

std::unique_ptr<Discretization> make_vrm() { return std::make_unique<Vrm>(false); }
std::unique_ptr<Discretization> make_corrected_vrm() { return std::make_unique<Vrm>(true); }

}  // namespace corrlap

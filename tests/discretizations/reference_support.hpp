#pragma once
// Helpers shared by the discretization tests: the reference mesh and normals, entry-wise matrix
// comparison as scripts/mtxdiff.py does it, and small meshes.
#include <Eigen/Sparse>
#include <cmath>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/discretizations/assembly/detail/face_kernel_isa.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace corrlap::test {

inline std::string sphere_ref(const std::string& file) { return reference_dir() + "/sphere1_h0.2/" + file; }

struct ReferenceCase {
  SurfelMesh mesh;
  NormalFields normals;
};

inline const ReferenceCase& reference_case() {
  static const ReferenceCase c = [] {
    ReferenceCase r;
    r.mesh = to_surfel_mesh(read_obj(sphere_ref("mesh.obj")), "reference mesh");
    r.normals.face = read_normals(sphere_ref("face_normals_true.txt"));
    r.normals.vertex = read_normals(sphere_ref("vertex_normals_true.txt"));
    return r;
  }();
  return c;
}

/// max |A - B| / max |B| over the union of the patterns, and the number of positions where exactly
/// one side has a value above 1e-14 * max|B| (the mtxdiff.py criterion: explicit zeros don't count).
struct MatrixDiff {
  double relative = 0.0;
  int pattern_mismatch = 0;
};

inline MatrixDiff compare_matrices(const Eigen::SparseMatrix<double>& A, const Eigen::SparseMatrix<double>& B) {
  MatrixDiff d;
  if (A.rows() != B.rows() || A.cols() != B.cols()) {
    d.relative = INFINITY;
    return d;
  }
  double scale = 0.0;
  for (int c = 0; c < B.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(B, c); it; ++it) scale = std::max(scale, std::abs(it.value()));
  if (scale == 0.0) scale = 1.0;
  const Eigen::SparseMatrix<double> diff = A - B;
  double worst = 0.0;
  for (int c = 0; c < diff.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(diff, c); it; ++it)
      worst = std::max(worst, std::abs(it.value()));
  d.relative = worst / scale;
  auto significant = [&](const Eigen::SparseMatrix<double>& X) {
    Eigen::SparseMatrix<double> S = X;
    S.prune([&](Eigen::Index, Eigen::Index, double v) { return std::abs(v) > 1e-14 * scale; });
    for (int c = 0; c < S.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(S, c); it; ++it) it.valueRef() = 1.0;
    return S;
  };
  const Eigen::SparseMatrix<double> pa = significant(A), pb = significant(B);
  const Eigen::SparseMatrix<double> pd = pa - pb;
  for (int c = 0; c < pd.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(pd, c); it; ++it)
      if (it.value() != 0.0) ++d.pattern_mismatch;
  return d;
}

}  // namespace corrlap::test

#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/surface/implicit_shape.hpp>

namespace corrlap::test {
/// Every instruction set of the per-face kernels that this machine runs (Best = what assembly picks).
inline std::vector<detail::FaceKernelIsa> face_kernel_isas() {
  std::vector<detail::FaceKernelIsa> isas = {detail::FaceKernelIsa::Scalar, detail::FaceKernelIsa::Sse2,
                                             detail::FaceKernelIsa::Best};
  if (detail::cpu_has_avx2()) isas.push_back(detail::FaceKernelIsa::Avx2);
  return isas;
}
}  // namespace corrlap::test

namespace corrlap::test {

/// sphere1 (centre c) digitized at h in the box -2..2, with true (radial) face and vertex normals
/// (docs/math.md §12.3: u_v = x_v/|x_v|, u_f = b_f/|b_f|).
struct SphereCase {
  SurfelMesh mesh;
  NormalFields normals;
};
inline SphereCase sphere_case(double h, const Eigen::Vector3d& center = Eigen::Vector3d::Zero()) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -2.0;
  p.max_aabb = 2.0;
  const ImplicitShape shape = make_implicit_shape("sphere1", center);
  SphereCase s;
  s.mesh = extract_surface(digitize(shape, p));
  s.normals.face = true_face_normals(shape, s.mesh);
  s.normals.vertex = true_vertex_normals(shape, s.mesh);
  return s;
}

/// Rows of `n` tilted by deterministic noise of relative size `amount` and renormalized: normals like
/// an estimator's (integral invariants), off the true ones by a few degrees and not smooth.
inline Eigen::MatrixX3d perturbed_normals(const Eigen::MatrixX3d& n, double amount, unsigned seed) {
  Eigen::MatrixX3d p = n;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    for (int c = 0; c < 3; ++c) p(i, c) += amount * std::sin(1.7 * double(i) + 2.3 * c + 0.61 * seed);
    p.row(i).normalize();
  }
  return p;
}

/// A digitized shape ("sphere1" in [-2, 2]^3, "torus" (R = 6, r = 2) in [-9, 9]^3) with its true
/// normals, or II-like perturbed ones (perturbed_normals, 0.15).
inline SphereCase shape_case(const std::string& shape_name, double h, bool perturbed) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = shape_name == "torus" ? -9.0 : -2.0;
  p.max_aabb = -p.min_aabb;
  const ImplicitShape shape = make_implicit_shape(shape_name);
  SphereCase s;
  s.mesh = extract_surface(digitize(shape, p));
  s.normals.face = true_face_normals(shape, s.mesh);
  s.normals.vertex = true_vertex_normals(shape, s.mesh);
  if (perturbed) {
    s.normals.face = perturbed_normals(s.normals.face, 0.15, 1);
    s.normals.vertex = perturbed_normals(s.normals.vertex, 0.15, 2);
  }
  return s;
}

/// Flat square grid in the plane z = 0 with n x n quads of side h, counter-clockwise seen from +z
/// (no surfel data), and u = e_z everywhere.
inline SphereCase flat_grid(int n, double h) {
  SphereCase s;
  s.mesh.positions.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) s.mesh.positions.row(j * (n + 1) + i) = Eigen::RowVector3d(i * h, j * h, 0.0);
  s.mesh.faces.resize(n * n, 4);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int v = j * (n + 1) + i;
      s.mesh.faces.row(j * n + i) << v, v + 1, v + n + 2, v + n + 1;
    }
  s.mesh.h = h;
  s.normals.face = Eigen::MatrixX3d::Zero(n * n, 3);
  s.normals.face.col(2).setOnes();
  s.normals.vertex = Eigen::MatrixX3d::Zero((n + 1) * (n + 1), 3);
  s.normals.vertex.col(2).setOnes();
  return s;
}

inline double max_abs(const Eigen::SparseMatrix<double>& A) {
  double m = 0.0;
  for (int c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) m = std::max(m, std::abs(it.value()));
  return m;
}

/// max |A - B| / max |B| (dense-free).
inline double relative_difference(const Eigen::SparseMatrix<double>& A, const Eigen::SparseMatrix<double>& B) {
  return max_abs(A - B) / std::max(max_abs(B), 1e-300);
}

}  // namespace corrlap::test

#ifdef CORRLAP_CLI
namespace corrlap::test {
/// Like run_cli, but with output files named after `tag`: ctest runs test cases in parallel
/// processes whose run_cli counters collide on the same scratch file names.
inline int run_cli_tagged(const std::string& tag, const std::string& args, std::string* out = nullptr,
                          std::string* err = nullptr) {
  static int counter = 0;
  const std::string base = tmp_path("cli_" + tag + "_" + std::to_string(++counter));
  const std::string cmd = std::string(CORRLAP_CLI) + " " + args + " >" + base + ".out 2>" + base + ".err </dev/null";
  const int status = std::system(cmd.c_str());
  if (out) *out = read_text(base + ".out");
  if (err) *err = read_text(base + ".err");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}
}  // namespace corrlap::test
#endif

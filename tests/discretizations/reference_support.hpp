#pragma once
// Helpers shared by the discretization tests: the reference mesh and normals, entry-wise matrix
// comparison as /work/shared/tools/mtxdiff.py does it, and small meshes.
#include <Eigen/Sparse>
#include <cmath>
#include <string>

#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>

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
    for (Eigen::SparseMatrix<double>::InnerIterator it(diff, c); it; ++it) worst = std::max(worst, std::abs(it.value()));
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

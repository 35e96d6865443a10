#pragma once
// Test-only operators for the backend tests: the flat bilinear FEM of docs/math.md §4.5 (corrected FEM
// with trivial normals, x = y = 0, z = 1) on a digitized sphere. L is negative semi-definite,
// M the consistent mass (docs/math.md §4.4). Independent of the discretizations library on purpose.
#include <Eigen/Sparse>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <string>

namespace corrlap::test {

struct FlatFem {
  SurfelMesh mesh;
  Eigen::SparseMatrix<double> L, M;
};

/// The flat FEM on the digitization of a named shape of make_implicit_shape in [-bbox, bbox]^3.
inline FlatFem flat_fem_shape(const std::string& shape, double h, double bbox, double radius_scale = 1.0) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -bbox;
  p.max_aabb = bbox;
  FlatFem r;
  r.mesh = extract_surface(digitize(make_implicit_shape(shape), p));
  // docs/math.md §4.5: standard bilinear stiffness; docs/math.md §4.4: consistent mass h^2/36 [...].
  const double K[4][4] = {{4, -1, -2, -1}, {-1, 4, -1, -2}, {-2, -1, 4, -1}, {-1, -2, -1, 4}};
  const double Mm[4][4] = {{4, 2, 1, 2}, {2, 4, 2, 1}, {1, 2, 4, 2}, {2, 1, 2, 4}};
  const double hh = h * radius_scale;
  std::vector<Eigen::Triplet<double>> tl, tm;
  for (int f = 0; f < r.mesh.num_faces(); ++f)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        tl.emplace_back(r.mesh.faces(f, i), r.mesh.faces(f, j), -K[i][j] / 6.0);
        tm.emplace_back(r.mesh.faces(f, i), r.mesh.faces(f, j), hh * hh * Mm[i][j] / 36.0);
      }
  const int n = r.mesh.num_vertices();
  r.L.resize(n, n);
  r.M.resize(n, n);
  r.L.setFromTriplets(tl.begin(), tl.end());
  r.M.setFromTriplets(tm.begin(), tm.end());
  r.L.makeCompressed();
  r.M.makeCompressed();
  return r;
}

inline FlatFem flat_fem_sphere(double h, double radius_scale = 1.0) {
  return flat_fem_shape("sphere1", h, 2.0, radius_scale);
}

/// -L + c M: symmetric positive definite for c > 0, same pattern for every c.
inline Eigen::SparseMatrix<double> shifted(const FlatFem& op, double c) {
  Eigen::SparseMatrix<double> A = -op.L + c * op.M;
  A.makeCompressed();
  return A;
}

}  // namespace corrlap::test

// Backward Poisson convergence (docs/math.md §10.4) of corrected VRM on sphere1 with true normals.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>

#include "discretizations/test_vrm_support.hpp"

using namespace corrlap;

TEST_CASE("corrected VRM backward Poisson error on sphere1 decreases with order >= 1.5 (docs/math.md §10.4)") {
  const double hs[3] = {0.1, 0.05, 0.025};
  double err[3];
  const ImplicitShape sphere = make_implicit_shape("sphere1");
  const auto d = make_discretization("corrected-vrm");
  for (int i = 0; i < 3; ++i) {
    const SurfelMesh mesh = test::sphere1_surface(hs[i]);
    NormalFields nf;
    nf.vertex = true_vertex_normals(sphere, mesh);
    const Operators ops = d->assemble(mesh, nf, Config());
    CHECK(ops.warnings.empty());
    err[i] = test::backward_poisson_error(ops.L, ops.M, test::radial(mesh.positions));
  }
  const double o1 = std::log(err[0] / err[1]) / std::log(2.0), o2 = std::log(err[1] / err[2]) / std::log(2.0);
  MESSAGE("corrected-vrm backward L2 errors " << err[0] << " " << err[1] << " " << err[2] << ", orders " << o1 << " "
                                              << o2);
  CHECK(err[1] < err[0]);
  CHECK(err[2] < err[1]);
  CHECK(std::log(err[0] / err[2]) / std::log(4.0) >= 1.5);
  CHECK(o2 >= 1.5);
}

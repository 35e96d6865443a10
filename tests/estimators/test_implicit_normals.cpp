// True normals (docs/math.md §1.5): damped Newton projection and the reference's true normals.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>

#include "test_support.hpp"

using namespace corrlap;

TEST_CASE("true face normals equal the reference face_normals_true on sphere1 h=0.2") {
  DigitizationParams p;
  p.h = 0.2;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  const ImplicitShape s = make_implicit_shape("sphere1");
  const SurfelMesh m = extract_surface(digitize(s, p));
  const Eigen::MatrixX3d ref = read_normals(test::reference_dir() + "/sphere1_h0.2/face_normals_true.txt");
  CHECK((true_face_normals(s, m) - ref).cwiseAbs().maxCoeff() < 1e-14);
  // The sphere shortcut (radial) agrees with the general path: gradient at the projected point.
  const Eigen::MatrixX3d c = m.face_centroids();
  double diff = 0;
  for (Eigen::Index f = 0; f < c.rows(); ++f) {
    const Eigen::Vector3d n = s.gradient(project_onto_surface(s, c.row(f).transpose())).normalized();
    diff = std::max(diff, (n.transpose() - ref.row(f)).cwiseAbs().maxCoeff());
  }
  CHECK(diff < 1e-12);
}

TEST_CASE("projection reaches |P| < accuracy within 20 damped steps on goursat surfels") {
  DigitizationParams p;
  p.h = 0.5;
  const ImplicitShape s = make_implicit_shape("goursat");
  const SurfelMesh m = extract_surface(digitize(s, p));
  const Eigen::MatrixX3d c = m.face_centroids();
  int converged = 0;
  double worst_angle = 0;
  for (Eigen::Index f = 0; f < c.rows(); ++f) {
    const Eigen::Vector3d q = project_onto_surface(s, c.row(f).transpose());
    converged += std::abs(s.value(q)) < 1e-4;
    // The fully converged projection gives (almost) the same normal.
    ProjectionParams tight;
    tight.max_iterations = 200;
    tight.accuracy = 1e-12;
    const Eigen::Vector3d n = true_normal(s, c.row(f).transpose());
    const Eigen::Vector3d nt = true_normal(s, c.row(f).transpose(), tight);
    worst_angle = std::max(worst_angle, std::acos(std::min(1.0, n.dot(nt))));
    CHECK((q - c.row(f).transpose()).norm() < p.h);  // moved less than a voxel
  }
  CHECK(converged == c.rows());
  CHECK(worst_angle < 1e-3);
}

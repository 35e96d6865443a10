// Every registered discretization assembled from many TBB tasks at once, on two meshes in turn,
// without a pattern and through one QuadPattern per mesh shared by all tasks (its lazy parts and
// scratch pool are then used concurrently): every result must equal the serial one bit for bit.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/discretizations/assembly/quad_pattern.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <thread>
#include <vector>

#include "stress/concurrently.hpp"

using namespace corrlap;

namespace {
// Assemblies in flight at once (at least 4, more on larger machines).
const int kLanes = int(std::max(4u, std::thread::hardware_concurrency()));

struct Case {
  SurfelMesh mesh;
  NormalFields normals;
};

Case make_case(double h, const Eigen::Vector3d& centre) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -2;
  p.max_aabb = 2;
  const ImplicitShape shape = make_implicit_shape("sphere1", centre);
  Case c;
  c.mesh = extract_surface(digitize(shape, p));
  c.normals.face = true_face_normals(shape, c.mesh);
  c.normals.vertex = vertex_normals_from_face_normals(c.normals.face, c.mesh.faces, c.mesh.num_vertices());
  return c;
}

bool identical(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
  for (Eigen::Index k = 0; k <= a.outerSize(); ++k)
    if (a.outerIndexPtr()[k] != b.outerIndexPtr()[k]) return false;
  for (Eigen::Index k = 0; k < a.nonZeros(); ++k)
    if (a.innerIndexPtr()[k] != b.innerIndexPtr()[k] || a.valuePtr()[k] != b.valuePtr()[k]) return false;
  return true;
}
}  // namespace

TEST_CASE("concurrent assembly of every method equals the serial result bitwise") {
  const std::vector<Case> cases = {make_case(0.1, Eigen::Vector3d(0.01, 0.02, -0.03)),
                                   make_case(0.125, Eigen::Vector3d(-0.02, 0.0, 0.04))};
  const std::vector<std::string> methods = discretization_registry().names();
  REQUIRE(methods.size() >= 8);
  // Serial results first.
  std::vector<std::vector<Operators>> expected(methods.size());
  for (std::size_t m = 0; m < methods.size(); ++m)
    for (const Case& c : cases)
      expected[m].push_back(make_discretization(methods[m])->assemble(c.mesh, c.normals, Config()));
  constexpr int kRounds = 24;
  std::atomic<int> mismatches{0}, runs{0};
  test::concurrently(int(methods.size()) * kRounds, kLanes, [&](int task) {
    const std::size_t m = std::size_t(task) % methods.size();
    const std::size_t c = std::size_t(task / int(methods.size())) % cases.size();
    const Operators ops = make_discretization(methods[m])->assemble(cases[c].mesh, cases[c].normals, Config());
    if (!identical(ops.L, expected[m][c].L) || !identical(ops.M, expected[m][c].M)) ++mismatches;
    ++runs;
  });
  CHECK(runs == int(methods.size()) * kRounds);
  CHECK(mismatches == 0);
}

TEST_CASE("concurrent assemblies sharing one QuadPattern equal the serial result bitwise") {
  const std::vector<Case> cases = {make_case(0.1, Eigen::Vector3d(0.01, 0.02, -0.03)),
                                   make_case(0.125, Eigen::Vector3d(-0.02, 0.0, 0.04))};
  const std::vector<std::string> methods = {"fem", "interpolated", "polydec", "projected-polydec",
                                            "vrm", "corrected-vrm"};
  const std::vector<Config> params = {Config(), Config::from_key_values({"mass=lumped"}),
                                      Config::from_key_values({"assembly=local"})};
  auto config_for = [&](std::size_t m, std::size_t variant) {
    if (variant == 1 && (methods[m] == "fem" || methods[m] == "corrected-vrm")) return params[1];
    if (variant == 1 && methods[m] == "interpolated") return params[2];
    return params[0];
  };
  std::vector<std::vector<std::vector<Operators>>> expected(methods.size());
  for (std::size_t m = 0; m < methods.size(); ++m)
    for (std::size_t variant = 0; variant < 2; ++variant) {
      expected[m].emplace_back();
      for (const Case& c : cases)
        expected[m][variant].push_back(
            make_discretization(methods[m])->assemble(c.mesh, c.normals, config_for(m, variant)));
    }
  // Fresh patterns: the first concurrent users race to build the lazy projection pattern.
  const std::vector<QuadPattern> patterns = {QuadPattern::build(cases[0].mesh), QuadPattern::build(cases[1].mesh)};
  constexpr int kRounds = 16;
  const int tasks = int(methods.size()) * 2 * kRounds;
  std::atomic<int> mismatches{0}, runs{0};
  test::concurrently(tasks, kLanes, [&](int task) {
    const std::size_t m = std::size_t(task) % methods.size();
    const std::size_t variant = std::size_t(task / int(methods.size())) % 2;
    const std::size_t c = std::size_t(task / int(2 * methods.size())) % cases.size();
    const auto d = make_discretization(methods[m]);
    Operators ops = d->assemble(cases[c].mesh, cases[c].normals, config_for(m, variant), patterns[c]);
    if (!identical(ops.L, expected[m][variant][c].L) || !identical(ops.M, expected[m][variant][c].M)) ++mismatches;
    // Refill through the same shared pattern.
    d->assemble_into(cases[c].mesh, cases[c].normals, config_for(m, variant), patterns[c], ops);
    if (!identical(ops.L, expected[m][variant][c].L) || !identical(ops.M, expected[m][variant][c].M)) ++mismatches;
    ++runs;
  });
  CHECK(runs == tasks);
  CHECK(mismatches == 0);
}

// Every registered discretization assembled from many TBB tasks at once, on two meshes in turn
// (so shared caches keyed by connectivity are replaced while other tasks use them): every result
// must equal the serial one bit for bit.
#include <doctest/doctest.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <vector>

#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>

using namespace corrlap;

namespace {
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
    for (const Case& c : cases) expected[m].push_back(make_discretization(methods[m])->assemble(c.mesh, c.normals, Config()));
  constexpr int kRounds = 24;
  std::atomic<int> mismatches{0}, runs{0};
  tbb::parallel_for(0, int(methods.size()) * kRounds, [&](int task) {
    const std::size_t m = std::size_t(task) % methods.size();
    const std::size_t c = std::size_t(task / int(methods.size())) % cases.size();
    const Operators ops = make_discretization(methods[m])->assemble(cases[c].mesh, cases[c].normals, Config());
    if (!identical(ops.L, expected[m][c].L) || !identical(ops.M, expected[m][c].M)) ++mismatches;
    ++runs;
  });
  CHECK(runs == int(methods.size()) * kRounds);
  CHECK(mismatches == 0);
}

// The free functions of discretizations/methods.hpp are the registry path, bit for bit.
#include <doctest/doctest.h>

#include <corrlap/corrlap.hpp>
#include <cstring>

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {
struct Sphere {
  SurfelMesh mesh;
  NormalFields normals;
};
const Sphere& sphere() {
  static const Sphere s = [] {
    const ImplicitShape shape = make_implicit_shape("sphere1");
    Sphere r;
    r.mesh = extract_surface(digitize(shape, {.h = 0.2, .min_aabb = -1.5, .max_aabb = 1.5}));
    NormalRequest request;
    request.source = NormalSource::True;
    r.normals = resolve_normals(r.mesh, NormalKind::Vertex, request, &shape);
    return r;
  }();
  return s;
}

// Same pattern and the same bits in every stored value.
bool identical(const SpMat& a, const SpMat& b) {
  SpMat x = a, y = b;
  x.makeCompressed();
  y.makeCompressed();
  if (x.rows() != y.rows() || x.cols() != y.cols() || x.nonZeros() != y.nonZeros()) return false;
  const auto n = std::size_t(x.nonZeros());
  return std::memcmp(x.outerIndexPtr(), y.outerIndexPtr(), sizeof(int) * std::size_t(x.outerSize() + 1)) == 0 &&
         std::memcmp(x.innerIndexPtr(), y.innerIndexPtr(), sizeof(int) * n) == 0 &&
         std::memcmp(x.valuePtr(), y.valuePtr(), sizeof(double) * n) == 0;
}
}  // namespace

TEST_CASE("every free function gives the registry's matrices bit for bit (sphere1, h = 0.2)") {
  const Sphere& s = sphere();
  const Eigen::MatrixX3d& fn = s.normals.face;
  const Eigen::MatrixX3d& vn = s.normals.vertex;
  const Config lambda = Config::from_key_values({"lambda=0.3"});
  struct Case {
    std::string name;
    Operators ops;
    Config options;
  };
  std::vector<Case> cases;
  cases.push_back({"fem", corrected_fem(s.mesh, fn), {}});
  cases.push_back({"interpolated", interpolated(s.mesh, vn), {}});
  cases.push_back({"interpolated", interpolated(s.mesh, vn, lambda), lambda});
  cases.push_back({"polydec", polydec(s.mesh), {}});
  cases.push_back({"projected-polydec", projected_polydec(s.mesh, fn), {}});
  cases.push_back({"vrm", vrm(s.mesh), {}});
  cases.push_back({"corrected-vrm", corrected_vrm(s.mesh, vn), {}});
  cases.push_back({"heat-kernel", heat_kernel(s.mesh, fn), {}});
  cases.push_back({"cotan", cotan(s.mesh), {}});
  std::vector<std::string> covered;
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const Operators ref = make_discretization(c.name)->assemble(s.mesh, s.normals, c.options);
    CHECK(c.ops.L.nonZeros() > 0);
    CHECK(identical(c.ops.L, ref.L));
    CHECK(identical(c.ops.M, ref.M));
    CHECK(c.ops.domain == ref.domain);
    // Sign convention of the header: L 1 = 0 (to rounding) and negative diagonal.
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(c.ops.L.cols());
    CHECK((c.ops.L * ones).lpNorm<Eigen::Infinity>() < 1e-12 * c.ops.L.diagonal().cwiseAbs().maxCoeff());
    CHECK(c.ops.L.diagonal().maxCoeff() < 0.0);
    covered.push_back(c.name);
  }
  for (const std::string& name : discretization_registry().names()) {
    CAPTURE(name);
    CHECK(std::find(covered.begin(), covered.end(), name) != covered.end());
  }
  // Shapes documented in methods.hpp: #V x #V, the heat kernel's default on faces.
  CHECK(cases[0].ops.L.rows() == s.mesh.num_vertices());
  CHECK(cases[7].ops.L.rows() == s.mesh.num_faces());
  // The wrappers pass the options through: a different lambda, a different L.
  CHECK(!identical(cases[1].ops.L, cases[2].ops.L));
  CHECK_THROWS_WITH_AS(corrected_fem(s.mesh, fn, Config::from_key_values({"lamda=1"})), doctest::Contains("lamda"),
                       InputError);
  CHECK_THROWS_AS(interpolated(s.mesh, fn), InputError);  // face normals where vertex normals belong
}

#include "test_functions.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>

namespace corrlap {

namespace {
// P6(z) = (231 z^6 - 315 z^4 + 105 z^2 - 5) / 16, a degree-6 zonal harmonic: Delta f = -42 f (docs/math.md §10.2).
double p6(const Eigen::Vector3d& q) {
  const double z2 = q.z() * q.z();
  return (((231.0 * z2 - 315.0) * z2 + 105.0) * z2 - 5.0) / 16.0;
}
}  // namespace

const std::vector<TestFunction>& test_functions() {
  // docs/math.md §10.2: Delta_{S^2} f = Delta F - q^T (grad^2 F) q - 2 q . grad F for the ambient F.
  static const std::vector<TestFunction> list = {
      {"x2", "f = x^2, Delta f = 2 - 6x^2", [](const Eigen::Vector3d& q) { return q.x() * q.x(); },
       [](const Eigen::Vector3d& q) { return 2.0 - 6.0 * q.x() * q.x(); }},
      {"expx", "f = e^x, Delta f = e^x (1 - 2x - x^2)", [](const Eigen::Vector3d& q) { return std::exp(q.x()); },
       [](const Eigen::Vector3d& q) { return std::exp(q.x()) * (1.0 - 2.0 * q.x() - q.x() * q.x()); }},
      {"p6", "f = P6(z) = (231z^6 - 315z^4 + 105z^2 - 5)/16, Delta f = -42 f", p6,
       [](const Eigen::Vector3d& q) { return -42.0 * p6(q); }},
  };
  return list;
}

bool has_test_function(const std::string& name) {
  for (const auto& t : test_functions())
    if (t.name == name) return true;
  return false;
}

const TestFunction& test_function(const std::string& name) {
  std::string names;
  for (const auto& t : test_functions()) {
    if (t.name == name) return t;
    names += " " + t.name;
  }
  throw InputError("unknown test function '" + name + "'; available:" + names);
}

TestFunctionSamples sample_on_unit_sphere(const TestFunction& function, const Eigen::MatrixX3d& positions,
                                          const Eigen::Vector3d& center) {
  const Eigen::Index n = positions.rows();
  TestFunctionSamples s;
  s.f.resize(n);
  s.laplacian.resize(n);
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Vector3d x = positions.row(v).transpose() - center;
    const double r = x.norm();
    if (!(r > 0.0) || !std::isfinite(r))
      throw InputError("test function " + function.name + ": vertex " + std::to_string(v) +
                       " has no radial projection onto the unit sphere (it is at the centre or not finite)");
    const Eigen::Vector3d q = x / r;
    s.f[v] = function.value(q);
    s.laplacian[v] = function.laplacian(q);
  }
  return s;
}

}  // namespace corrlap

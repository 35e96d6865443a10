#pragma once
// Test functions of docs/math.md §10.2 on the unit sphere: values u(q) and their exact Laplace-Beltrami
// Delta_{S^2} u(q) at points q with |q| = 1, looked up by the names the CLI uses (--rhs).
#include <Eigen/Core>
#include <string>
#include <vector>

namespace corrlap {

struct TestFunction {
  std::string name;         ///< registry name: x2, expx, p6
  std::string description;  ///< formula, e.g. "f = x^2, Delta f = 2 - 6x^2"
  double (*value)(const Eigen::Vector3d& q);
  double (*laplacian)(const Eigen::Vector3d& q);  ///< Delta_{S^2} value at q, |q| = 1
};

/// Every built-in test function: x2 (f = x^2), expx (f = e^x), p6 (degree-6 zonal harmonic P6(z)).
const std::vector<TestFunction>& test_functions();
/// The test function named `name`; InputError listing the names otherwise.
const TestFunction& test_function(const std::string& name);
bool has_test_function(const std::string& name);

/// Samples at the vertices (docs/math.md §10.1): f[v] = u(q_v), laplacian[v] = Delta u(q_v) with
/// q_v = (x_v - c) / |x_v - c| the radial projection onto the unit sphere of centre c.
struct TestFunctionSamples {
  Eigen::VectorXd f;          ///< #V
  Eigen::VectorXd laplacian;  ///< #V
};
/// `positions` is #V x 3. InputError when a vertex sits at the centre (no projection).
TestFunctionSamples sample_on_unit_sphere(const TestFunction& function, const Eigen::MatrixX3d& positions,
                                          const Eigen::Vector3d& center = Eigen::Vector3d::Zero());

}  // namespace corrlap

#pragma once
// Trivariate polynomials P(x, y, z) with a parser for strings such as "x^2+y^2+z^2-1" (docs/math.md §1.1).
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace corrlap {

/// Dense trivariate polynomial: coefficient c[i][j][k] of x^i y^j z^k.
/// Evaluation follows the reference's recursive scheme (see operator()), so that digitizations
/// agree voxel for voxel.
class Polynomial {
 public:
  Polynomial() = default;
  /// The constant polynomial c.
  explicit Polynomial(double c);
  /// The monomial x (axis 0), y (axis 1) or z (axis 2).
  static Polynomial variable(int axis);

  /// Parses + - * / ^ (non-negative integer exponent), numbers (1, 2.5, 1e-3), x y z (also X Y Z)
  /// and parentheses. Division is allowed by constants only. Throws InputError naming the
  /// position and the problem.
  static Polynomial parse(std::string_view text);

  double operator()(double x, double y, double z) const;
  double operator()(const Eigen::Vector3d& p) const { return (*this)(p.x(), p.y(), p.z()); }
  Eigen::Vector3d gradient(const Eigen::Vector3d& p) const;
  /// d/d(axis) as a polynomial.
  Polynomial derivative(int axis) const;

  /// Conservative range of P over the box lo..hi (interval arithmetic on the monomials),
  /// widened by a relative rounding margin so that "hi < 0" really means P < 0 everywhere.
  void bounds(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double& min_value, double& max_value) const;

  int degree(int axis) const { return deg_[axis]; }
  int total_degree() const;
  bool is_zero() const;
  double coefficient(int i, int j, int k) const;
  std::string to_string() const;

  Polynomial operator+(const Polynomial& q) const;
  Polynomial operator-(const Polynomial& q) const;
  Polynomial operator*(const Polynomial& q) const;
  Polynomial operator-() const;
  Polynomial pow(int e) const;

 private:
  void resize(int dx, int dy, int dz);
  void trim();
  double& at(int i, int j, int k) { return c_[(std::size_t(i) * (deg_[1] + 1) + j) * (deg_[2] + 1) + k]; }
  double at(int i, int j, int k) const { return c_[(std::size_t(i) * (deg_[1] + 1) + j) * (deg_[2] + 1) + k]; }

  int deg_[3] = {0, 0, 0};
  std::vector<double> c_ = {0.0};
};

}  // namespace corrlap

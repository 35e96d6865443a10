#pragma once
// Trivariate polynomials P(x, y, z) with a parser for strings such as "x^2+y^2+z^2-1" (docs/math.md §1.1).
#include <Eigen/Core>
#include <cstddef>
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

  /// Limits of parse(): far above what the named shapes need (total degree 6, depth 3), low
  /// enough that a short hostile string cannot expand for seconds or overflow the stack.
  static constexpr int kMaxParseDegree = 64;    ///< total degree of every intermediate result
  static constexpr int kMaxParseDepth = 200;    ///< nested parentheses and unary signs
  static constexpr double kMaxParseWork = 2e7;  ///< coefficient operations of the whole expansion

  /// Parses + - * / ^ (non-negative integer exponent), numbers (1, 2.5, 1e-3), x y z (also X Y Z)
  /// and parentheses. Division is allowed by constants only. Throws InputError naming the
  /// position and the problem: syntax, a non-finite coefficient, or a limit above exceeded
  /// (checked before each product is expanded).
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
  /// Number of nonzero coefficients.
  std::size_t term_count() const;
  /// Number of stored coefficients, (deg_x + 1)(deg_y + 1)(deg_z + 1).
  std::size_t dense_size() const { return c_.size(); }
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

/// grad P with its three derivative polynomials formed once: operator()(p) equals P.gradient(p) bit
/// for bit without differentiating at every call (Newton projections call it millions of times).
class PolynomialGradient {
 public:
  explicit PolynomialGradient(const Polynomial& p) : d_{p.derivative(0), p.derivative(1), p.derivative(2)} {}
  Eigen::Vector3d operator()(const Eigen::Vector3d& p) const { return {d_[0](p), d_[1](p), d_[2](p)}; }
  /// d/d(axis) P.
  const Polynomial& derivative(int axis) const { return d_[axis]; }

 private:
  Polynomial d_[3];
};

}  // namespace corrlap

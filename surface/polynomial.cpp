#include "polynomial.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <limits>
#include <sstream>

namespace corrlap {

Polynomial::Polynomial(double c) : c_{c} {}

Polynomial Polynomial::variable(int axis) {
  Polynomial p;
  int d[3] = {0, 0, 0};
  d[axis] = 1;
  p.resize(d[0], d[1], d[2]);
  p.at(d[0], d[1], d[2]) = 1.0;
  return p;
}

void Polynomial::resize(int dx, int dy, int dz) {
  std::vector<double> c(std::size_t(dx + 1) * (dy + 1) * (dz + 1), 0.0);
  for (int i = 0; i <= std::min(dx, deg_[0]); ++i)
    for (int j = 0; j <= std::min(dy, deg_[1]); ++j)
      for (int k = 0; k <= std::min(dz, deg_[2]); ++k) c[(std::size_t(i) * (dy + 1) + j) * (dz + 1) + k] = at(i, j, k);
  c_.swap(c);
  deg_[0] = dx;
  deg_[1] = dy;
  deg_[2] = dz;
}

void Polynomial::trim() {
  int d[3] = {0, 0, 0};
  for (int i = 0; i <= deg_[0]; ++i)
    for (int j = 0; j <= deg_[1]; ++j)
      for (int k = 0; k <= deg_[2]; ++k)
        if (at(i, j, k) != 0.0) {
          d[0] = std::max(d[0], i);
          d[1] = std::max(d[1], j);
          d[2] = std::max(d[2], k);
        }
  if (d[0] != deg_[0] || d[1] != deg_[1] || d[2] != deg_[2]) resize(d[0], d[1], d[2]);
}

double Polynomial::coefficient(int i, int j, int k) const {
  if (i < 0 || j < 0 || k < 0 || i > deg_[0] || j > deg_[1] || k > deg_[2]) return 0.0;
  return at(i, j, k);
}

int Polynomial::total_degree() const {
  int d = 0;
  for (int i = 0; i <= deg_[0]; ++i)
    for (int j = 0; j <= deg_[1]; ++j)
      for (int k = 0; k <= deg_[2]; ++k)
        if (at(i, j, k) != 0.0) d = std::max(d, i + j + k);
  return d;
}

std::size_t Polynomial::term_count() const {
  return std::size_t(std::count_if(c_.begin(), c_.end(), [](double v) { return v != 0.0; }));
}

bool Polynomial::is_zero() const {
  return std::all_of(c_.begin(), c_.end(), [](double v) { return v == 0.0; });
}

double Polynomial::operator()(double x, double y, double z) const {
  // Same arithmetic as the reference's recursive evaluation: sum over increasing powers, each
  // power accumulated by repeated multiplication, x outermost and z innermost. Matching it
  // matters for sample points that lie exactly on {P = 0}, where rounding decides inside/outside.
  double sx = 0.0, px = 1.0;
  for (int i = 0; i <= deg_[0]; ++i) {
    double sy = 0.0, py = 1.0;
    for (int j = 0; j <= deg_[1]; ++j) {
      double sz = 0.0, pz = 1.0;
      for (int k = 0; k <= deg_[2]; ++k) {
        sz += at(i, j, k) * pz;
        pz *= z;
      }
      sy += sz * py;
      py *= y;
    }
    sx += sy * px;
    px *= x;
  }
  return sx;
}

Polynomial Polynomial::derivative(int axis) const {
  int d[3] = {deg_[0], deg_[1], deg_[2]};
  if (d[axis] == 0) return Polynomial(0.0);
  d[axis] -= 1;
  Polynomial r;
  r.resize(d[0], d[1], d[2]);
  for (int i = 0; i <= d[0]; ++i)
    for (int j = 0; j <= d[1]; ++j)
      for (int k = 0; k <= d[2]; ++k) {
        int s[3] = {i, j, k};
        s[axis] += 1;
        r.at(i, j, k) = double(s[axis]) * at(s[0], s[1], s[2]);
      }
  r.trim();
  return r;
}

Eigen::Vector3d Polynomial::gradient(const Eigen::Vector3d& p) const {
  // Small polynomials: differentiate on the fly (cheap relative to I/O of the callers).
  return {derivative(0)(p), derivative(1)(p), derivative(2)(p)};
}

namespace {
// Range of t^e over [lo, hi].
void power_range(double lo, double hi, int e, double& pmin, double& pmax) {
  if (e == 0) {
    pmin = pmax = 1.0;
    return;
  }
  const double a = std::pow(lo, e), b = std::pow(hi, e);
  if (e % 2 == 1) {
    pmin = a;
    pmax = b;
  } else if (lo >= 0.0) {
    pmin = a;
    pmax = b;
  } else if (hi <= 0.0) {
    pmin = b;
    pmax = a;
  } else {
    pmin = 0.0;
    pmax = std::max(a, b);
  }
}
}  // namespace

void Polynomial::bounds(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double& min_value,
                        double& max_value) const {
  double mn = 0.0, mx = 0.0, magnitude = 0.0;
  for (int i = 0; i <= deg_[0]; ++i)
    for (int j = 0; j <= deg_[1]; ++j)
      for (int k = 0; k <= deg_[2]; ++k) {
        const double c = at(i, j, k);
        if (c == 0.0) continue;
        double r[3][2];
        power_range(lo.x(), hi.x(), i, r[0][0], r[0][1]);
        power_range(lo.y(), hi.y(), j, r[1][0], r[1][1]);
        power_range(lo.z(), hi.z(), k, r[2][0], r[2][1]);
        double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b)
            for (int d = 0; d < 2; ++d) {
              const double v = c * r[0][a] * r[1][b] * r[2][d];
              tmin = std::min(tmin, v);
              tmax = std::max(tmax, v);
            }
        mn += tmin;
        mx += tmax;
        magnitude += std::max(std::abs(tmin), std::abs(tmax));
      }
  // Horner evaluation and this bound both round; 1e-10 relative is far above either error.
  const double margin = 1e-10 * magnitude + std::numeric_limits<double>::min();
  min_value = mn - margin;
  max_value = mx + margin;
}

Polynomial Polynomial::operator+(const Polynomial& q) const {
  Polynomial r = *this;
  r.resize(std::max(deg_[0], q.deg_[0]), std::max(deg_[1], q.deg_[1]), std::max(deg_[2], q.deg_[2]));
  for (int i = 0; i <= q.deg_[0]; ++i)
    for (int j = 0; j <= q.deg_[1]; ++j)
      for (int k = 0; k <= q.deg_[2]; ++k) r.at(i, j, k) += q.at(i, j, k);
  r.trim();
  return r;
}

Polynomial Polynomial::operator-() const {
  Polynomial r = *this;
  for (double& v : r.c_) v = -v;
  return r;
}

Polynomial Polynomial::operator-(const Polynomial& q) const {
  Polynomial r = *this;
  r.resize(std::max(deg_[0], q.deg_[0]), std::max(deg_[1], q.deg_[1]), std::max(deg_[2], q.deg_[2]));
  for (int i = 0; i <= q.deg_[0]; ++i)
    for (int j = 0; j <= q.deg_[1]; ++j)
      for (int k = 0; k <= q.deg_[2]; ++k) r.at(i, j, k) -= q.at(i, j, k);
  r.trim();
  return r;
}

Polynomial Polynomial::operator*(const Polynomial& q) const {
  Polynomial r;
  r.resize(deg_[0] + q.deg_[0], deg_[1] + q.deg_[1], deg_[2] + q.deg_[2]);
  for (int i = 0; i <= deg_[0]; ++i)
    for (int j = 0; j <= deg_[1]; ++j)
      for (int k = 0; k <= deg_[2]; ++k) {
        const double a = at(i, j, k);
        if (a == 0.0) continue;
        for (int u = 0; u <= q.deg_[0]; ++u)
          for (int v = 0; v <= q.deg_[1]; ++v)
            for (int w = 0; w <= q.deg_[2]; ++w) r.at(i + u, j + v, k + w) += a * q.at(u, v, w);
      }
  r.trim();
  return r;
}

Polynomial Polynomial::pow(int e) const {
  Polynomial r(1.0);
  for (int i = 0; i < e; ++i) r = r * (*this);
  return r;
}

std::string Polynomial::to_string() const {
  std::ostringstream os;
  os.precision(17);
  bool first = true;
  const char* names = "xyz";
  for (int i = deg_[0]; i >= 0; --i)
    for (int j = deg_[1]; j >= 0; --j)
      for (int k = deg_[2]; k >= 0; --k) {
        const double c = at(i, j, k);
        if (c == 0.0) continue;
        if (!first)
          os << (c < 0 ? " - " : " + ");
        else if (c < 0)
          os << "-";
        first = false;
        const double a = std::abs(c);
        const int e[3] = {i, j, k};
        bool printed = false;
        if (a != 1.0 || i + j + k == 0) {
          os << a;
          printed = true;
        }
        for (int ax = 0; ax < 3; ++ax) {
          if (e[ax] == 0) continue;
          if (printed) os << "*";
          os << names[ax];
          if (e[ax] > 1) os << "^" << e[ax];
          printed = true;
        }
      }
  if (first) os << "0";
  return os.str();
}

// ---- parser ------------------------------------------------------------------------------
namespace {

class Parser {
 public:
  explicit Parser(std::string_view s) : s_(s) {}

  Polynomial parse_all() {
    skip();
    if (pos_ >= s_.size()) fail("empty polynomial");
    Polynomial p = expr();
    skip();
    if (pos_ < s_.size()) fail(std::string("unexpected character '") + s_[pos_] + "'");
    // Products of large finite coefficients (1e200*1e200) or a division by a tiny constant.
    for (int i = 0; i <= p.degree(0); ++i)
      for (int j = 0; j <= p.degree(1); ++j)
        for (int k = 0; k <= p.degree(2); ++k)
          if (!std::isfinite(p.coefficient(i, j, k))) {
            pos_ = 0;
            fail("non-finite coefficient after expansion (overflow)");
          }
    return p;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    std::ostringstream os;
    // Long inputs are shown by their beginning: the position locates the problem.
    os << "polynomial \"" << (s_.size() <= 80 ? std::string(s_) : std::string(s_.substr(0, 80)) + "...")
       << "\": " << what << " at position " << pos_ + 1;
    throw InputError(os.str());
  }
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skip();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  // Charges `work` coefficient operations to the budget of the whole parse, before doing them.
  void charge(double work, std::size_t at) {
    work_ += work;
    if (work_ > Polynomial::kMaxParseWork) {
      pos_ = at;
      std::ostringstream os;
      os << "expansion too large (more than " << Polynomial::kMaxParseWork << " coefficient operations)";
      fail(os.str());
    }
  }
  static double dense_size(const int d[3]) { return double(d[0] + 1) * double(d[1] + 1) * double(d[2] + 1); }
  // p * q with the degree and work limits checked before expanding (operator* costs terms(p) x
  // dense(q) multiply-adds plus the dense result).
  Polynomial multiply(const Polynomial& p, const Polynomial& q, std::size_t at) {
    const int total = p.total_degree() + q.total_degree();
    if (total > Polynomial::kMaxParseDegree) {
      pos_ = at;
      fail("total degree " + std::to_string(total) + " exceeds the limit " +
           std::to_string(Polynomial::kMaxParseDegree));
    }
    const int d[3] = {p.degree(0) + q.degree(0), p.degree(1) + q.degree(1), p.degree(2) + q.degree(2)};
    charge(double(p.term_count()) * double(q.dense_size()) + dense_size(d), at);
    return p * q;
  }
  Polynomial add(const Polynomial& p, const Polynomial& q, bool subtract, std::size_t at) {
    const int d[3] = {std::max(p.degree(0), q.degree(0)), std::max(p.degree(1), q.degree(1)),
                      std::max(p.degree(2), q.degree(2))};
    charge(2 * dense_size(d), at);
    return subtract ? p - q : p + q;
  }
  Polynomial expr() {
    Polynomial p = term();
    for (;;) {
      const std::size_t at = pos_;
      if (accept('+'))
        p = add(p, term(), false, at);
      else if (accept('-'))
        p = add(p, term(), true, at);
      else
        return p;
    }
  }
  Polynomial term() {
    Polynomial p = unary();
    for (;;) {
      const std::size_t op = pos_;
      if (accept('*')) {
        p = multiply(p, unary(), op);
      } else if (accept('/')) {
        const std::size_t at = pos_;
        Polynomial q = unary();
        if (q.total_degree() != 0) {
          pos_ = at;
          fail("division by a non-constant expression");
        }
        const double c = q(0.0, 0.0, 0.0);
        if (c == 0.0) {
          pos_ = at;
          fail("division by zero");
        }
        p = multiply(p, Polynomial(1.0 / c), op);
      } else {
        return p;
      }
    }
  }
  // Every level of nesting, "(" or a unary sign, passes here: the depth bound keeps the recursion
  // far from the stack limit (30 000 parentheses used to overflow it).
  Polynomial unary() {
    if (++depth_ > Polynomial::kMaxParseDepth)
      fail("nesting deeper than " + std::to_string(Polynomial::kMaxParseDepth) + " levels (parentheses and signs)");
    Polynomial p;
    if (accept('-'))
      p = -unary();
    else if (accept('+'))
      p = unary();
    else
      p = power();
    --depth_;
    return p;
  }
  Polynomial power() {
    Polynomial base = primary();
    const std::size_t op = pos_;
    if (accept('^')) {
      skip();
      const std::size_t start = pos_;
      while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      if (start == pos_) fail("expected a non-negative integer exponent after '^'");
      // Digits are accumulated with a cap (no std::stol, whose out_of_range would escape).
      const std::string_view digits = s_.substr(start, pos_ - start);
      long e = 0;
      for (char ch : digits) e = std::min<long>(10 * e + (ch - '0'), 1000000);
      if (e > Polynomial::kMaxParseDegree) {
        pos_ = start;
        fail("exponent " + std::string(digits.substr(0, 20)) + (digits.size() > 20 ? "..." : "") +
             " exceeds the limit " + std::to_string(Polynomial::kMaxParseDegree));
      }
      const long total = e * base.total_degree();
      if (total > Polynomial::kMaxParseDegree) {
        pos_ = op;
        fail("total degree " + std::to_string(total) + " of the power exceeds the limit " +
             std::to_string(Polynomial::kMaxParseDegree));
      }
      // Same arithmetic as Polynomial::pow (r = r * base, e times), with the work charged per step.
      Polynomial r(1.0);
      for (long i = 0; i < e; ++i) r = multiply(r, base, op);
      return r;
    }
    return base;
  }
  Polynomial primary() {
    skip();
    if (pos_ >= s_.size()) fail("unexpected end of expression");
    const char c = s_[pos_];
    if (c == '(') {
      ++pos_;
      Polynomial p = expr();
      if (!accept(')')) fail("missing ')'");
      return p;
    }
    if (c == 'x' || c == 'X') return ++pos_, Polynomial::variable(0);
    if (c == 'y' || c == 'Y') return ++pos_, Polynomial::variable(1);
    if (c == 'z' || c == 'Z') return ++pos_, Polynomial::variable(2);
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      const std::size_t start = pos_;
      while (pos_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '.')) ++pos_;
      if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
        std::size_t q = pos_ + 1;
        if (q < s_.size() && (s_[q] == '+' || s_[q] == '-')) ++q;
        if (q < s_.size() && std::isdigit(static_cast<unsigned char>(s_[q]))) {
          pos_ = q;
          while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
        }
      }
      const std::string num(s_.substr(start, pos_ - start));
      char* end = nullptr;
      const double v = std::strtod(num.c_str(), &end);
      if (end != num.c_str() + num.size()) {
        pos_ = start;
        fail("malformed number '" + num.substr(0, 40) + "'");
      }
      if (!std::isfinite(v)) {  // strtod turns 1e999 into inf
        pos_ = start;
        fail("non-finite coefficient '" + num.substr(0, 40) + "' (out of the range of double)");
      }
      return Polynomial(v);
    }
    fail(std::string("unexpected character '") + c + "'");
  }

  std::string_view s_;
  std::size_t pos_ = 0;
  int depth_ = 0;
  double work_ = 0;
};

}  // namespace

Polynomial Polynomial::parse(std::string_view text) { return Parser(text).parse_all(); }

}  // namespace corrlap

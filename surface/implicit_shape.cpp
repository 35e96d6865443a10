#include "implicit_shape.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <cstdint>
#include <limits>
#include <sstream>

#include "partial_digitization.hpp"

namespace corrlap {

double ImplicitShape::value(const Eigen::Vector3d& x) const {
  if (center.isZero()) return polynomial(x);
  return polynomial(x - center);
}

Eigen::Vector3d ImplicitShape::gradient(const Eigen::Vector3d& x) const {
  return polynomial.gradient(center.isZero() ? x : Eigen::Vector3d(x - center));
}

double ImplicitShape::sphere_radius() const {
  if (polynomial.degree(0) != 2 || polynomial.degree(1) != 2 || polynomial.degree(2) != 2) return 0.0;
  for (int i = 0; i <= 2; ++i)
    for (int j = 0; j <= 2; ++j)
      for (int k = 0; k <= 2; ++k) {
        const double c = polynomial.coefficient(i, j, k);
        const bool square =
            (i == 2 && j == 0 && k == 0) || (i == 0 && j == 2 && k == 0) || (i == 0 && j == 0 && k == 2);
        if (square && c != 1.0) return 0.0;
        if (!square && !(i == 0 && j == 0 && k == 0) && c != 0.0) return 0.0;
      }
  const double c0 = polynomial.coefficient(0, 0, 0);
  return c0 < 0.0 ? std::sqrt(-c0) : 0.0;
}

const std::vector<std::pair<std::string, std::string>>& named_shapes() {
  // docs/math.md §1.1 (the reference's getPolynomialList, exact strings)
  static const std::vector<std::pair<std::string, std::string>> list = {
      {"sphere1", "x^2+y^2+z^2-1"},
      {"sphere9", "x^2+y^2+z^2-81"},
      {"ellipsoid", "3*x^2+2*y^2+z^2-90"},
      {"cylinder", "x^2+2*z^2-90"},
      {"torus", "(x^2+y^2+z^2+6*6-2*2)^2-4*6*6*(x^2+y^2)"},
      {"rcube", "x^4+y^4+z^4-6561"},
      {"goursat", "-1*(8-0.03*x^4-0.03*y^4-0.03*z^4+2*x^2+2*y^2+2*z^2)"},
      {"goursat-hole", "x^4+y^4+z^4-2*4*(x^2+y^2+z^2)+2*4*4-2"},
      {"distel", "10000-(x^2+y^2+z^2+1000*(x^2+y^2)*(x^2+z^2)*(y^2+z^2))"},
      {"leopold", "(x^2*y^2*z^2+4*x^2+4*y^2+3*z^2)-100"},
      {"diabolo", "x^2-(y^2+z^2)^2"},
      {"heart", "-1*(x^2+2.25*y^2+z^2-1)^3+x^2*z^3+0.1125*y^2*z^3"},
      {"crixxi", "-0.9*(y^2+z^2-1)^2-(x^2+y^2-1)^3"},
  };
  return list;
}

ImplicitShape make_implicit_shape(std::string_view name_or_polynomial, const Eigen::Vector3d& center) {
  if (!center.allFinite()) throw InputError("implicit shape: the centre must be finite");
  ImplicitShape shape;
  shape.name = std::string(name_or_polynomial);
  shape.center = center;
  for (const auto& [name, text] : named_shapes()) {
    if (name == name_or_polynomial) {
      shape.polynomial = Polynomial::parse(text);
      return shape;
    }
  }
  bool has_variable = false;
  for (char c : name_or_polynomial)
    if (c == 'x' || c == 'y' || c == 'z' || c == 'X' || c == 'Y' || c == 'Z') has_variable = true;
  bool looks_like_name = !name_or_polynomial.empty();
  for (char c : name_or_polynomial)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_')) looks_like_name = false;
  if (looks_like_name && !has_variable) {
    std::ostringstream os;
    os << "unknown shape '" << name_or_polynomial << "'; known shapes:";
    for (const auto& [name, text] : named_shapes()) os << " " << name;
    os << " (or give a polynomial in x, y, z such as \"x^2+y^2+z^2-1\")";
    throw InputError(os.str());
  }
  shape.polynomial = Polynomial::parse(name_or_polynomial);
  if (shape.polynomial.total_degree() == 0)
    throw InputError("polynomial \"" + shape.name + "\" is constant: it defines no surface");
  return shape;
}

void digitization_box(const DigitizationParams& p, Eigen::Vector3i& lower, Eigen::Vector3i& upper) {
  if (!(p.h > 0.0) || !std::isfinite(p.h)) throw InputError("digitization: grid step h must be positive and finite");
  if (!(p.min_aabb < p.max_aabb) || !std::isfinite(p.min_aabb) || !std::isfinite(p.max_aabb))
    throw InputError("digitization: bounding box needs finite MIN < MAX");
  if (p.offset < 0) throw InputError("digitization: offset must be >= 0");
  const double lo = std::floor((p.min_aabb - p.offset * p.h) / p.h);
  const double hi = std::ceil((p.max_aabb + p.offset * p.h) / p.h);
  if (hi - lo > 100000.0) {
    std::ostringstream os;
    os << "digitization: box of " << (hi - lo + 1) << " voxels per axis is too large for h = " << p.h;
    throw InputError(os.str());
  }
  lower.setConstant(int(lo));
  upper.setConstant(int(hi));
}

namespace {

// P in two forms for digitization:
//  - the dense coefficients, evaluated row by row with exactly the operations (same order, same
//    powers by repeated multiplication, zero coefficients included) of Polynomial::operator(),
//    so that every voxel gets the bit of the voxel-by-voxel definition (docs/math.md §1.2);
//  - the non-zero monomials, for cheap conservative interval bounds over boxes.
class DigitizationKernel {
 public:
  explicit DigitizationKernel(const Polynomial& p) {
    for (int a = 0; a < 3; ++a) d_[a] = p.degree(a);
    dense_.resize(std::size_t(d_[0] + 1) * std::size_t(d_[1] + 1) * std::size_t(d_[2] + 1));
    for (int i = 0; i <= d_[0]; ++i)
      for (int j = 0; j <= d_[1]; ++j)
        for (int k = 0; k <= d_[2]; ++k) {
          const double c = p.coefficient(i, j, k);
          dense_[(std::size_t(i) * std::size_t(d_[1] + 1) + std::size_t(j)) * std::size_t(d_[2] + 1) + std::size_t(k)] =
              c;
          if (c != 0.0) terms_.push_back({i, j, k, c});
        }
  }
  int degree_x() const { return d_[0]; }

  /// Coefficients a_i (i = 0..deg_x) of P(., y, z): the inner sums "sy" of Polynomial::operator().
  void row_coefficients(double y, double z, double* a) const {
    for (int i = 0; i <= d_[0]; ++i) {
      const double* ci = dense_.data() + std::size_t(i) * std::size_t(d_[1] + 1) * std::size_t(d_[2] + 1);
      double sy = 0.0, py = 1.0;
      for (int j = 0; j <= d_[1]; ++j) {
        const double* cij = ci + std::size_t(j) * std::size_t(d_[2] + 1);
        double sz = 0.0, pz = 1.0;
        for (int k = 0; k <= d_[2]; ++k) {
          sz += cij[k] * pz;
          pz *= z;
        }
        sy += sz * py;
        py *= y;
      }
      a[i] = sy;
    }
  }
  /// The outer sum of Polynomial::operator() for the row coefficients a.
  double row_value(const double* a, double x) const {
    double sx = 0.0, px = 1.0;
    for (int i = 0; i <= d_[0]; ++i) {
      sx += a[i] * px;
      px *= x;
    }
    return sx;
  }

  /// Conservative range of P over [lo, hi] (same argument as Polynomial::bounds: interval
  /// products of monomial ranges, widened by 1e-10 of the term magnitudes, far above the
  /// rounding of both this bound and the evaluation). Powers by multiplication, not std::pow.
  void bounds(const double lo[3], const double hi[3], double& vmin, double& vmax) const {
    constexpr int kMaxDeg = 64;
    double r[3][kMaxDeg + 1][2];
    for (int a = 0; a < 3; ++a) {
      double pl = 1.0, ph = 1.0;
      r[a][0][0] = r[a][0][1] = 1.0;
      for (int e = 1; e <= std::min(d_[a], kMaxDeg); ++e) {
        pl *= lo[a];
        ph *= hi[a];
        if (e % 2 == 1 || lo[a] >= 0.0) {
          r[a][e][0] = pl;
          r[a][e][1] = ph;
        } else if (hi[a] <= 0.0) {
          r[a][e][0] = ph;
          r[a][e][1] = pl;
        } else {
          r[a][e][0] = 0.0;
          r[a][e][1] = std::max(pl, ph);
        }
      }
    }
    double mn = 0.0, mx = 0.0, magnitude = 0.0;
    for (const Term& t : terms_) {
      if (t.i > kMaxDeg || t.j > kMaxDeg || t.k > kMaxDeg) {  // absurd degree: give up culling
        vmin = -std::numeric_limits<double>::infinity();
        vmax = std::numeric_limits<double>::infinity();
        return;
      }
      const double* rx = r[0][t.i];
      const double* ry = r[1][t.j];
      const double* rz = r[2][t.k];
      double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) {
          const double xy = t.c * rx[a] * ry[b];
          const double v0 = xy * rz[0], v1 = xy * rz[1];
          tmin = std::min(tmin, std::min(v0, v1));
          tmax = std::max(tmax, std::max(v0, v1));
        }
      mn += tmin;
      mx += tmax;
      magnitude += std::max(std::abs(tmin), std::abs(tmax));
    }
    const double margin = 1e-10 * magnitude + std::numeric_limits<double>::min();
    vmin = mn - margin;
    vmax = mx + margin;
  }

 private:
  struct Term {
    int i, j, k;
    double c;
  };
  int d_[3] = {0, 0, 0};
  std::vector<double> dense_;
  std::vector<Term> terms_;
};

// Recursive culling of one tile of the grid. Tiles are 64-aligned in x (one word per row), so
// tasks on different tiles write disjoint words.
struct DigitizeTile {
  const DigitizationKernel& kernel;
  VoxelGrid& grid;
  double h;
  bool centred;
  Eigen::Vector3d c;

  // Leaf: at most this many voxels are evaluated exactly without further bounding.
  // Leaf size and the preference for splitting y and z before x: measured best of
  // {16, 64, 256} x {1, 2, 4, 8, 16} on sphere1 at h = 0.0025 (bench_digitization).
  static constexpr int kLeafVoxels = 64;
  static constexpr int kRowWeight = 4;

  void fill(const int z0[3], const int z1[3]) const {
    const int lx0 = z0[0] - grid.lower().x(), lx1 = z1[0] - grid.lower().x();
    const std::size_t w = std::size_t(lx0 >> 6);
    const int b0 = lx0 & 63, b1 = b0 + (lx1 - lx0);
    const std::uint64_t mask =
        (b1 == 63 ? ~std::uint64_t{0} : (std::uint64_t{2} << b1) - 1) & ~((std::uint64_t{1} << b0) - 1);
    for (int z = z0[2]; z <= z1[2]; ++z)
      for (int y = z0[1]; y <= z1[1]; ++y) grid.row(y, z)[w] |= mask;
  }

  // DigitizationKernel::row_value at x = x0 .. x0+count-1 for degree D in x, operation by
  // operation (sx = 0; px = 1; sx += a_i px; px *= x), so the values are bitwise identical.
  template <int D>
  void row_values(const double* a, int x0, int count, double* out) const {
    const double cx = centred ? c.x() : 0.0;
    for (int k = 0; k < count; ++k) {
      double x = (x0 + k) * h;
      if (centred) x = x - cx;
      double sx = 0.0, px = 1.0;
      for (int i = 0; i <= D; ++i) {
        sx += a[i] * px;
        px *= x;
      }
      out[k] = sx;
    }
  }

  void evaluate(const int z0[3], const int z1[3]) const {
    const int lx0 = z0[0] - grid.lower().x();
    const std::size_t w = std::size_t(lx0 >> 6);
    double a[65];
    const int dx = kernel.degree_x();
    std::vector<double> heap;
    double* coef = a;
    if (dx + 1 > 65) {
      heap.resize(std::size_t(dx) + 1);
      coef = heap.data();
    }
    for (int z = z0[2]; z <= z1[2]; ++z)
      for (int y = z0[1]; y <= z1[1]; ++y) {
        double py = y * h, pz = z * h;
        if (centred) {
          py = py - c.y();
          pz = pz - c.z();
        }
        kernel.row_coefficients(py, pz, coef);
        double values[64];
        const int count = z1[0] - z0[0] + 1;  // <= 64: a leaf lies in one word
        switch (dx) {  // fixed degree: the loop over x vectorizes (lanes = voxels, same operations)
          case 0:
            row_values<0>(coef, z0[0], count, values);
            break;
          case 1:
            row_values<1>(coef, z0[0], count, values);
            break;
          case 2:
            row_values<2>(coef, z0[0], count, values);
            break;
          case 3:
            row_values<3>(coef, z0[0], count, values);
            break;
          case 4:
            row_values<4>(coef, z0[0], count, values);
            break;
          case 5:
            row_values<5>(coef, z0[0], count, values);
            break;
          case 6:
            row_values<6>(coef, z0[0], count, values);
            break;
          default:
            for (int k = 0; k < count; ++k) {
              double px = (z0[0] + k) * h;
              if (centred) px = px - c.x();
              values[k] = kernel.row_value(coef, px);
            }
        }
        std::uint64_t bits = 0;
        for (int k = 0; k < count; ++k) bits |= std::uint64_t(values[k] <= 0.0) << k;
        grid.row(y, z)[w] |= bits << (lx0 & 63);
      }
  }

  void operator()(const int z0[3], const int z1[3]) const {
    // z*h is monotone in z, so the interval [z0*h, z1*h] contains every sample point.
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = z0[a] * h;
      hi[a] = z1[a] * h;
      if (centred) {
        lo[a] -= c[a];
        hi[a] -= c[a];
        lo[a] -= 1e-12 * (1.0 + std::abs(lo[a]));
        hi[a] += 1e-12 * (1.0 + std::abs(hi[a]));
      }
    }
    double vmin, vmax;
    kernel.bounds(lo, hi, vmin, vmax);
    if (vmin > 0.0) return;  // all outside: bits are already 0
    if (vmax <= 0.0) return fill(z0, z1);
    int ext[3], longest = 0;
    for (int a = 0; a < 3; ++a) ext[a] = z1[a] - z0[a] + 1;
    // Leaves elongated along x: one row-coefficient evaluation then serves several voxels.
    const int score[3] = {ext[0], kRowWeight * ext[1], kRowWeight * ext[2]};
    for (int a = 1; a < 3; ++a)
      if (score[a] > score[longest]) longest = a;
    if (std::int64_t(ext[0]) * ext[1] * ext[2] <= kLeafVoxels || ext[longest] == 1) return evaluate(z0, z1);
    int m0[3] = {z0[0], z0[1], z0[2]}, m1[3] = {z1[0], z1[1], z1[2]};
    const int mid = z0[longest] + ext[longest] / 2;
    m1[longest] = mid - 1;
    (*this)(z0, m1);
    m0[longest] = mid;
    (*this)(m0, z1);
  }
};

// The voxels of [lower, upper] (a sub-box of the reference's box or the whole of it).
VoxelGrid digitize_box(const ImplicitShape& shape, double h, const Eigen::Vector3i& lower,
                       const Eigen::Vector3i& upper) {
  VoxelGrid grid(lower, upper, h);
  const Eigen::Vector3i n = grid.size();
  const DigitizationKernel kernel(shape.polynomial);
  const DigitizeTile tile{kernel, grid, h, !shape.center.isZero(), shape.center};
  // Tiles of 64^3 voxels (x: one word), culled recursively by interval bounds; only the voxels
  // of leaves the bounds cannot decide are evaluated (docs/math.md §1.2: result identical to voxel by voxel).
  constexpr int T = 64;
  const int tx = (n.x() + T - 1) / T, ty = (n.y() + T - 1) / T, tz = (n.z() + T - 1) / T;
  tbb::parallel_for(0, tx * ty * tz, [&](int t) {
    const int ix = t % tx, iy = (t / tx) % ty, iz = t / (tx * ty);
    const int z0[3] = {lower.x() + ix * T, lower.y() + iy * T, lower.z() + iz * T};
    const int z1[3] = {std::min(z0[0] + T - 1, upper.x()), std::min(z0[1] + T - 1, upper.y()),
                       std::min(z0[2] + T - 1, upper.z())};
    tile(z0, z1);
  });
  return grid;
}

}  // namespace

VoxelGrid digitize(const ImplicitShape& shape, const DigitizationParams& params) {
  Eigen::Vector3i lower, upper;
  digitization_box(params, lower, upper);
  return digitize_box(shape, params.h, lower, upper);
}

VoxelGrid digitize_x_range(const ImplicitShape& shape, const DigitizationParams& params, int x_first, int x_last) {
  Eigen::Vector3i lower, upper;
  digitization_box(params, lower, upper);
  lower.x() = std::max(lower.x(), x_first);
  upper.x() = std::min(upper.x(), x_last);
  if (lower.x() > upper.x()) throw InputError("digitization: the slab of x is outside the box");
  return digitize_box(shape, params.h, lower, upper);
}

}  // namespace corrlap

#include "implicit_shape.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <sstream>

#include "error.hpp"

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
        const bool square = (i == 2 && j == 0 && k == 0) || (i == 0 && j == 2 && k == 0) ||
                            (i == 0 && j == 0 && k == 2);
        if (square && c != 1.0) return 0.0;
        if (!square && !(i == 0 && j == 0 && k == 0) && c != 0.0) return 0.0;
      }
  const double c0 = polynomial.coefficient(0, 0, 0);
  return c0 < 0.0 ? std::sqrt(-c0) : 0.0;
}

const std::vector<std::pair<std::string, std::string>>& named_shapes() {
  // spec §1.1 (the reference's getPolynomialList, exact strings)
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
  if (!(p.h > 0.0) || !std::isfinite(p.h))
    throw InputError("digitization: grid step h must be positive and finite");
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

VoxelGrid digitize(const ImplicitShape& shape, const DigitizationParams& params) {
  Eigen::Vector3i lower, upper;
  digitization_box(params, lower, upper);
  VoxelGrid grid(lower, upper, params.h);
  const double h = params.h;
  const Eigen::Vector3i n = grid.size();
  constexpr int B = 8;  // block edge in voxels
  const int bx = (n.x() + B - 1) / B, by = (n.y() + B - 1) / B, bz = (n.z() + B - 1) / B;
  const bool centred = !shape.center.isZero();
  const Eigen::Vector3d c = shape.center;

  // One block-slab (fixed block z index) per task: tasks write disjoint rows of the grid.
  tbb::parallel_for(0, bz, [&](int kb) {
    for (int jb = 0; jb < by; ++jb)
      for (int ib = 0; ib < bx; ++ib) {
        const Eigen::Vector3i z0(lower.x() + ib * B, lower.y() + jb * B, lower.z() + kb * B);
        const Eigen::Vector3i z1 = (z0 + Eigen::Vector3i::Constant(B - 1)).cwiseMin(upper);
        // z*h is monotone in z, so the interval [z0*h, z1*h] contains every sample point.
        Eigen::Vector3d lo(z0.x() * h, z0.y() * h, z0.z() * h);
        Eigen::Vector3d hi(z1.x() * h, z1.y() * h, z1.z() * h);
        if (centred) {
          lo -= c;
          hi -= c;
          lo.array() -= 1e-12 * (1.0 + lo.array().abs());
          hi.array() += 1e-12 * (1.0 + hi.array().abs());
        }
        double vmin, vmax;
        shape.polynomial.bounds(lo, hi, vmin, vmax);
        if (vmin > 0.0) continue;  // all outside: bits are already 0
        const bool all_inside = vmax <= 0.0;
        for (int z = z0.z(); z <= z1.z(); ++z)
          for (int y = z0.y(); y <= z1.y(); ++y) {
            std::uint64_t* row = grid.row(y, z);
            for (int x = z0.x(); x <= z1.x(); ++x) {
              bool in = all_inside;
              if (!all_inside) {
                const double px = x * h, py = y * h, pz = z * h;
                in = (centred ? shape.polynomial(px - c.x(), py - c.y(), pz - c.z())
                              : shape.polynomial(px, py, pz)) <= 0.0;
              }
              if (in) {
                const int lx = x - lower.x();
                row[lx >> 6] |= std::uint64_t{1} << (lx & 63);
              }
            }
          }
      }
  });
  return grid;
}

}  // namespace corrlap

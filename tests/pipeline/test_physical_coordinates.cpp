// Volumes in physical coordinates (docs/io.md, "Physical coordinates"): the inside rules (label,
// threshold, nonzero), the labels of a segmentation, anisotropic voxels resampled to cubes of the
// finest spacing, and the regularized surface of an anisotropic scan against the true shape, in
// millimetres.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <cstdint>
#include <vector>

using namespace corrlap;

namespace {

// The semi-axes and centre of the test ellipsoid, in millimetres: a scan-like blob a few
// centimetres across, off the voxel grid.
const Eigen::Vector3d kAxes(16.0, 12.0, 10.0);
const Eigen::Vector3d kCentre(0.3, 0.2, 0.1);

// The ellipsoid sampled at voxel centres of the given spacing (uint8 0/1, i fastest), the voxels'
// physical centres origin + spacing * index.
struct SampledVolume {
  std::vector<std::uint8_t> values;
  Eigen::Vector3i size;
  VolumeGeometry geometry;

  VolumeArrayInput input() const {
    VolumeArrayInput in;
    in.size = size;
    in.data = values.data();
    in.type = VoxelValueType::UInt8;
    in.strides = {1, size.x(), std::ptrdiff_t(size.x()) * size.y()};
    in.geometry = geometry;
    return in;
  }
  bool inside(int i, int j, int k) const {
    return values[(std::size_t(k) * std::size_t(size.y()) + std::size_t(j)) * std::size_t(size.x()) + std::size_t(i)] !=
           0;
  }
};

SampledVolume sampled_ellipsoid(const Eigen::Vector3d& spacing) {
  SampledVolume v;
  v.geometry.spacing = spacing;
  for (int a = 0; a < 3; ++a) {
    v.size[a] = 2 * int(std::ceil((kAxes[a] + 2.0 * spacing[a]) / spacing[a])) + 1;
    v.geometry.origin[a] = -spacing[a] * (v.size[a] / 2);
  }
  v.values.assign(std::size_t(v.size.prod()), 0);
  for (int k = 0; k < v.size.z(); ++k)
    for (int j = 0; j < v.size.y(); ++j)
      for (int i = 0; i < v.size.x(); ++i) {
        const Eigen::Vector3d p = v.geometry.to_physical(Eigen::Vector3d(i, j, k)) - kCentre;
        if (p.cwiseQuotient(kAxes).squaredNorm() <= 1.0)
          v.values[(std::size_t(k) * std::size_t(v.size.y()) + std::size_t(j)) * std::size_t(v.size.x()) +
                   std::size_t(i)] = 1;
      }
  return v;
}

// Distance from p to the ellipsoid: Newton's iterations on the closest point's Lagrange parameter
// (exact to rounding for a point near the surface).
double distance_to_ellipsoid(const Eigen::Vector3d& point) {
  const Eigen::Vector3d p = (point - kCentre).cwiseAbs();
  const Eigen::Vector3d a2 = kAxes.cwiseProduct(kAxes);
  // Closest point q = a^2 p / (a^2 + t): f(t) = sum (a p / (a^2 + t))^2 - 1 = 0.
  double t = 0.0;
  for (int it = 0; it < 100; ++it) {
    double f = -1.0, df = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double r = kAxes[c] * p[c] / (a2[c] + t);
      f += r * r;
      df += -2.0 * r * r / (a2[c] + t);
    }
    const double step = f / df;
    t -= step;
    t = std::max(t, -a2.minCoeff() + 1e-12);
    if (std::abs(step) < 1e-14 * (1.0 + std::abs(t))) break;
  }
  Eigen::Vector3d q;
  for (int c = 0; c < 3; ++c) q[c] = a2[c] * p[c] / (a2[c] + t);
  return (p - q).norm();
}

struct Regularized {
  Eigen::MatrixX3d physical;  // the regularized vertices, in millimetres
  double mean_distance = 0.0, max_distance = 0.0;
};

// `corrlap regularize` (II normals from the voxels), in physical coordinates, with the same II
// radius in millimetres for every scan (3 voxels of the coarsest, 2.5 mm, scan: the ball must span
// a step of its staircase), so that the scans differ by their voxels only.
Regularized regularize_physical(const SampledVolume& v) {
  const LoadedSurface s = load_surface(v.input());
  NormalRequest request;
  // In (resampled) voxels: radius k h^alpha = k h.
  request.ii = IIParams{.k = 7.5 / v.geometry.spacing.minCoeff(), .alpha = 1.0};
  const NormalFields n = resolve_normals(s, NormalKind::Vertex, request);
  // The three scans at one fixed alpha0: the automatic choice is off for resampled voxels
  // (pipeline/surface_defaults.cpp), and this compares the scans, not the choice.
  RegularizationOptions fixed;
  fixed.alpha0_auto = false;
  const RegularizedSurface r = regularize_surface(s.mesh, n, fixed);
  Regularized out;
  out.physical = s.frame.to_physical(r.mesh.positions);
  for (Eigen::Index i = 0; i < out.physical.rows(); ++i) {
    const double d = distance_to_ellipsoid(out.physical.row(i).transpose());
    out.mean_distance += d;
    out.max_distance = std::max(out.max_distance, d);
  }
  out.mean_distance /= double(out.physical.rows());
  return out;
}

}  // namespace

TEST_CASE("anisotropic voxels are resampled to cubes of the finest spacing, the frame maps to millimetres") {
  // Two by two by two voxels of 1 x 1 x 2 mm, origin (10, 20, 30): the labelled box spans
  // [9.5, 11.5] x [19.5, 21.5] x [29, 33] mm.
  const std::vector<std::uint8_t> ones(8, 1);
  VolumeArrayInput in;
  in.size = {2, 2, 2};
  in.data = ones.data();
  in.type = VoxelValueType::UInt8;
  in.strides = {1, 2, 4};
  in.geometry.spacing = {1.0, 1.0, 2.0};
  in.geometry.origin = {10.0, 20.0, 30.0};
  const LoadedSurface s = load_surface(in);
  CHECK(s.grid->count() == 2 * 2 * 4);
  REQUIRE(s.frame.geometry());
  CHECK(s.frame.geometry()->isotropic());
  CHECK(s.h == doctest::Approx(2.0 / 4.0));  // the resampled longest side (4 voxels) spans 2
  const Eigen::MatrixX3d p = s.frame.to_physical(s.mesh.positions);
  CHECK(p.colwise().minCoeff().isApprox(Eigen::RowVector3d(9.5, 19.5, 29.0)));
  CHECK(p.colwise().maxCoeff().isApprox(Eigen::RowVector3d(11.5, 21.5, 33.0)));
  CHECK(s.frame.length_to_physical(s.h) == doctest::Approx(1.0));  // a resampled voxel is 1 mm
  CHECK(!s.frame.mirrors());
  // A direction of determinant -1 (a flipped axis) mirrors: writers reverse the faces.
  in.geometry.direction = Eigen::Vector3d(-1.0, 1.0, 1.0).asDiagonal();
  const LoadedSurface m = load_surface(in);
  CHECK(m.frame.mirrors());
  const Eigen::MatrixX3d q = m.frame.to_physical(m.mesh.positions);
  CHECK(q.col(0).minCoeff() == doctest::Approx(8.5));  // x = 10 - i, i in [-1/2, 3/2]
  CHECK(q.col(0).maxCoeff() == doctest::Approx(10.5));
  // Normals follow the map: +x in index space is -x in physical space.
  const Eigen::MatrixX3d n = m.frame.normals_to_physical(Eigen::RowVector3d(1.0, 0.0, 0.0));
  CHECK(n.isApprox(Eigen::RowVector3d(-1.0, 0.0, 0.0)));
  // Degenerate geometry is refused, naming it.
  in.geometry.spacing = {1.0, 0.0, 2.0};
  CHECK_THROWS_WITH_AS(load_surface(in), doctest::Contains("voxel-to-physical map is degenerate"), InputError);
  // Without geometry, physical = voxel indices: pointels at half-integers.
  VolumeArrayInput plain = in;
  plain.geometry = VolumeGeometry{};
  const LoadedSurface u = load_surface(plain);
  const Eigen::MatrixX3d w = u.frame.to_physical(u.mesh.positions);
  CHECK(w.colwise().minCoeff().isApprox(Eigen::RowVector3d(-0.5, -0.5, -0.5)));
  CHECK(w.colwise().maxCoeff().isApprox(Eigen::RowVector3d(1.5, 1.5, 1.5)));
}

TEST_CASE("inside rules and labels: one label, every nonzero voxel, the labels of a segmentation") {
  // Three labels along x in a 7 x 3 x 3 volume: 1 at x = 1, 2 at x = 3, 5 at x = 5 (centre row only).
  VolumeData data;
  data.size = {7, 3, 3};
  data.type = VoxelValueType::Int16;
  std::vector<std::int16_t> v(std::size_t(data.size.prod()), 0);
  const auto at = [&](int x) { return std::size_t((1 * 3 + 1) * 7 + x); };
  v[at(1)] = 1;
  v[at(3)] = 2;
  v[at(5)] = 5;
  data.bytes.resize(v.size() * 2);
  std::memcpy(data.bytes.data(), v.data(), data.bytes.size());
  CHECK(volume_labels(data) == std::vector<double>{1.0, 2.0, 5.0});
  CHECK(load_surface(volume_array(data, InsideRule::nonzero())).grid->count() == 3);
  const LoadedSurface two = load_surface(volume_array(data, InsideRule::label(2.0)));
  CHECK(two.grid->count() == 1);
  CHECK(two.components == 1);
  CHECK(load_surface(volume_array(data, InsideRule::nonzero())).components == 3);  // all kept, counted
  CHECK(load_surface(volume_array(data, InsideRule::above(1.5))).grid->count() == 2);
  try {
    (void)load_surface(volume_array(data, InsideRule::label(3.0)));
    FAIL("an absent label was accepted");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("no voxel equal to the label 3") != std::string::npos);
    CHECK(e.parameter() == "label");
  }
  // A grey-level image has too many distinct values to be a segmentation.
  VolumeData grey;
  grey.size = {300, 300, 1};
  grey.type = VoxelValueType::Float32;
  std::vector<float> g(std::size_t(grey.size.prod()));
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = 1.0f + float(i);
  grey.bytes.resize(g.size() * 4);
  std::memcpy(grey.bytes.data(), g.data(), grey.bytes.size());
  CHECK_THROWS_WITH_AS(volume_labels(grey), doctest::Contains("looks like a grey-level image"), InputError);
  std::fill(grey.bytes.begin(), grey.bytes.end(), std::uint8_t{0});
  CHECK_THROWS_WITH_AS(volume_labels(grey), doctest::Contains("no nonzero value"), InputError);
}

TEST_CASE("an ellipsoid scanned at 1 x 1 x 2.5 mm regularizes within the isotropic scans' distances, in mm") {
  const Regularized fine = regularize_physical(sampled_ellipsoid({1.0, 1.0, 1.0}));
  const Regularized coarse = regularize_physical(sampled_ellipsoid({2.5, 2.5, 2.5}));
  const SampledVolume scan = sampled_ellipsoid({1.0, 1.0, 2.5});
  const Regularized aniso = regularize_physical(scan);
  MESSAGE("mean / max distance to the ellipsoid (mm): isotropic 1 mm "
          << fine.mean_distance << " / " << fine.max_distance << ", 1 x 1 x 2.5 mm " << aniso.mean_distance << " / "
          << aniso.max_distance << ", isotropic 2.5 mm " << coarse.mean_distance << " / " << coarse.max_distance);
  // The anisotropic scan holds more than the isotropic 2.5 mm one and less than the 1 mm one: its
  // surface must be at least as close as the coarse scan's (the test's tolerance: none), and stay
  // within the staircase's own error, half the coarsest voxel, of the true surface.
  CHECK(aniso.mean_distance <= coarse.mean_distance);
  CHECK(aniso.max_distance <= 0.5 * 2.5);
  CHECK(fine.mean_distance <= aniso.mean_distance);
  // Overlay: the vertices against the labelled boundary, the faces between inside and outside
  // voxels of the scan itself (boxes of 1 x 1 x 2.5 mm). Half an anisotropic voxel is half its
  // extent along each axis: the offset to the nearest boundary point is measured in the voxel's own
  // index units (each component over its axis's spacing), by its largest component. The true
  // ellipsoid is within 1/2 by that measure. The regularized surface is too, but on the caps of the
  // coarse axis, where a layer's step is a plateau a few voxels wide that the regularization
  // rounds: there it reaches 0.73 (the +z pole, 1.8 mm under the top layer's face and 0.66 mm under
  // the true pole). In millimetres it stays no farther from the labelled boundary than the true
  // surface does.
  struct Face {
    Eigen::Vector3d lo, hi;
    double thickness;
  };
  std::vector<Face> faces;
  const Eigen::Vector3d s = scan.geometry.spacing;
  for (int k = -1; k < scan.size.z(); ++k)
    for (int j = -1; j < scan.size.y(); ++j)
      for (int i = -1; i < scan.size.x(); ++i) {
        const auto in = [&](int a, int b, int c) {
          return a >= 0 && b >= 0 && c >= 0 && a < scan.size.x() && b < scan.size.y() && c < scan.size.z() &&
                 scan.inside(a, b, c);
        };
        const Eigen::Vector3i here(i, j, k);
        for (int axis = 0; axis < 3; ++axis) {
          Eigen::Vector3i next = here;
          ++next[axis];
          if (in(i, j, k) == in(next.x(), next.y(), next.z())) continue;
          Eigen::Vector3d c = scan.geometry.to_physical(here.cast<double>());
          Eigen::Vector3d half = 0.5 * s;
          c[axis] += 0.5 * s[axis];
          half[axis] = 0.0;
          faces.push_back({c - half, c + half, s[axis]});
        }
      }
  // Offset to the nearest boundary point, in the scan's voxels (largest component) and in millimetres.
  const auto to_boundary = [&](const Eigen::Vector3d& p, bool voxels) {
    double best = std::numeric_limits<double>::infinity();
    for (const Face& f : faces) {
      const Eigen::Vector3d offset = p - p.cwiseMax(f.lo).cwiseMin(f.hi);
      best = std::min(best, voxels ? offset.cwiseQuotient(s).cwiseAbs().maxCoeff() : offset.norm());
    }
    return best;
  };
  double worst_voxels = 0.0, worst_mm = 0.0, truth_voxels = 0.0, truth_mm = 0.0, off_caps = 0.0;
  int beyond_half = 0;
  for (Eigen::Index v = 0; v < aniso.physical.rows(); ++v) {
    const Eigen::Vector3d p = aniso.physical.row(v).transpose();
    const double d = to_boundary(p, true);
    worst_voxels = std::max(worst_voxels, d);
    worst_mm = std::max(worst_mm, to_boundary(p, false));
    if (d <= 0.5) continue;
    ++beyond_half;
    off_caps = std::max(off_caps, 1.0 - std::abs(p.z() - kCentre.z()) / kAxes.z());
  }
  for (int a = 0; a < 120; ++a)
    for (int b = 0; b <= 60; ++b) {
      const double phi = 2.0 * M_PI * a / 120.0, theta = M_PI * b / 60.0;
      const Eigen::Vector3d u(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      const Eigen::Vector3d p = kCentre + kAxes.cwiseProduct(u);
      truth_voxels = std::max(truth_voxels, to_boundary(p, true));
      truth_mm = std::max(truth_mm, to_boundary(p, false));
    }
  MESSAGE("largest offset to the labelled boundary: regularized "
          << worst_voxels << " voxel (" << worst_mm << " mm), true ellipsoid " << truth_voxels << " voxel (" << truth_mm
          << " mm); " << beyond_half << " of " << aniso.physical.rows() << " vertices beyond half a voxel");
  CHECK(truth_voxels <= 0.5);
  CHECK(worst_mm <= truth_mm);
  // The vertices beyond half a voxel are on the coarse axis's caps: in its outer three tenths.
  CHECK(beyond_half < aniso.physical.rows() / 100);
  CHECK(off_caps < 0.3);
}

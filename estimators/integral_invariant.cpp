#include "integral_invariant.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

namespace corrlap {

bool BallMoments::operator==(const BallMoments& o) const {
  return m0 == o.m0 && std::equal(m1, m1 + 3, o.m1) && std::equal(m2, m2 + 6, o.m2);
}

Eigen::Matrix3d BallMoments::covariance() const {
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  if (m0 == 0) return c;
  // docs/math.md §7 step 3: Cov = sum yy^T - (1/|Y|)(sum y)(sum y)^T. Translation invariant, so the exact
  // moments relative to the centre are used: no cancellation from large absolute coordinates.
  const double s[3] = {double(m1[0]), double(m1[1]), double(m1[2])};
  const int idx[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  const double inv = 1.0 / double(m0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(i, j) = double(m2[idx[i][j]]) - s[i] * s[j] * inv;
  return c;
}

IIParams default_ii_params(bool implicit_shape, std::optional<double> k, std::optional<double> alpha,
                           std::optional<bool> shrink_on_thin_parts) {
  IIParams p;
  if (!implicit_shape) p = IIParams{.k = kVoxelIIRadius, .alpha = 1.0, .shrink_on_thin_parts = true};
  if (k) p.k = *k;
  if (alpha) p.alpha = *alpha;
  if (shrink_on_thin_parts) p.shrink_on_thin_parts = *shrink_on_thin_parts;
  return p;
}

double ii_digital_radius(double h, const IIParams& params) {
  // docs/math.md §7 step 1: r_d = k * h^(alpha - 1); R = r_d * h.
  return params.k * std::pow(h, params.alpha - 1.0);
}

namespace {

/// Kernel predicate of docs/math.md §7 step 2: R - ||h delta|| >= 0 (closed ball).
bool in_kernel(int dx, int dy, int dz, double R, double h) {
  const double x = h * dx, y = h * dy, z = h * dz;
  return R - std::sqrt(x * x + y * y + z * z) >= 0.0;
}

/// One chord of the kernel: offsets (dy, dz), x offsets in [-w, w].
struct KernelRow {
  int dy, dz, w;
};

std::vector<KernelRow> kernel_rows(double digital_radius, double h) {
  const double R = digital_radius * h;
  const int n = int(std::ceil(digital_radius)) + 1;
  std::vector<KernelRow> rows;
  for (int dz = -n; dz <= n; ++dz)
    for (int dy = -n; dy <= n; ++dy) {
      if (!in_kernel(0, dy, dz, R, h)) continue;
      int w = 0;
      while (in_kernel(w + 1, dy, dz, R, h)) ++w;
      rows.push_back({dy, dz, w});
    }
  return rows;
}

}  // namespace

void ii_check_radius(int extent, double digital_radius) {
  if (!(digital_radius >= 1.0))
    throw InputError("II normals: digital radius r/h = " + std::to_string(digital_radius) +
                         " is smaller than one voxel (increase ii_radius, the II radius factor k, or use a finer h)",
                     "ii_radius");
  if (digital_radius > double(extent))
    throw InputError("II normals: digital radius r/h = " + std::to_string(digital_radius) +
                         " is larger than the volume (" + std::to_string(extent) +
                         " voxels); give a smaller ii_radius (while r/h stays at least 1)",
                     "ii_radius");
}

void ii_check_radius_fits_object(double across, double digital_radius) {
  if (digital_radius >= across) {
    std::ostringstream os;
    os << "II normals: the object is " << across
       << " voxels across (its bounding box's diagonal) and the II radius r/h = " << digital_radius
       << " voxels covers all of it from every surfel, so the normals would not see the surface; use "
       << "a smaller ii_radius (while r/h stays at least 1) or a finer resolution";
    throw InputError(os.str(), "ii_radius");
  }
}

namespace {

void check_radius(const VoxelGrid& grid, double digital_radius) {
  if (grid.empty_box()) throw InputError("II normals: the voxel grid is empty");
  ii_check_radius(grid.size().maxCoeff(), digital_radius);
}

// The diagonal of the object's bounding box, in voxels (0 for no vertex).
double object_across(const SurfelMesh& mesh, double h) {
  if (mesh.num_vertices() == 0) return 0.0;
  return (mesh.positions.colwise().maxCoeff() - mesh.positions.colwise().minCoeff()).norm() / h;
}

// A ball that covers the whole object from every surfel sees the same voxels everywhere: the
// normals would carry no information about the surface (on a single voxel they lie in the surfels'
// planes, which the operators then report as flipped).
void check_radius_fits_object(const SurfelMesh& mesh, double h, double digital_radius) {
  if (mesh.num_vertices() == 0) return;
  ii_check_radius_fits_object(object_across(mesh, h), digital_radius);
}

/// sum_{u=0}^{m} u^2 extended to negative m so that sum_{u=p}^{q} u^2 = G(q) - G(p-1).
inline std::int64_t G(std::int64_t m) { return m * (m + 1) * (2 * m + 1) / 6; }

/// Run-length encoding of every (y, z) row: runs of inside voxels as inclusive [begin, end] x ranges.
struct RowRuns {
  Eigen::Vector3i lower, size;
  std::vector<std::int64_t> offset;  // size ny*nz + 1
  std::vector<std::int32_t> runs;    // begin, end pairs (absolute x)

  std::size_t row_index(int y, int z) const {
    return std::size_t(z - lower.z()) * std::size_t(size.y()) + std::size_t(y - lower.y());
  }
};

/// Runs of set bits of one grid row, appended as absolute (begin, end) pairs; returns the count.
template <class Emit>
void scan_row(const std::uint64_t* words, int nx, int x0, Emit&& emit) {
  const int nw = (nx + 63) / 64;
  int start = -1;
  for (int wi = 0; wi < nw; ++wi) {
    std::uint64_t w = words[wi];
    if (wi == nw - 1 && (nx & 63)) w &= (std::uint64_t(1) << (nx & 63)) - 1;
    int pos = 0;
    while (pos < 64) {
      if (start < 0) {
        const std::uint64_t rest = pos == 0 ? w : (w >> pos);
        if (rest == 0) break;
        pos += __builtin_ctzll(rest);
        start = wi * 64 + pos;
      } else {
        const std::uint64_t rest = pos == 0 ? ~w : (~w >> pos);
        if (rest == 0) break;
        pos += __builtin_ctzll(rest);
        emit(x0 + start, x0 + wi * 64 + pos - 1);
        start = -1;
      }
    }
  }
  if (start >= 0) emit(x0 + start, x0 + nx - 1);
}

RowRuns encode_runs(const VoxelGrid& grid) {
  RowRuns rr;
  rr.lower = grid.lower();
  rr.size = grid.size();
  const int nx = rr.size.x(), ny = rr.size.y(), nz = rr.size.z();
  const std::size_t nrows = std::size_t(ny) * std::size_t(nz);
  std::vector<std::int64_t> count(nrows + 1, 0);
  tbb::parallel_for(0, nz, [&](int lz) {
    const int z = rr.lower.z() + lz;
    for (int y = rr.lower.y(); y < rr.lower.y() + ny; ++y) {
      std::int64_t c = 0;
      scan_row(grid.row(y, z), nx, rr.lower.x(), [&](int, int) { ++c; });
      count[rr.row_index(y, z)] = c;
    }
  });
  rr.offset.assign(nrows + 1, 0);
  for (std::size_t i = 0; i < nrows; ++i) rr.offset[i + 1] = rr.offset[i] + 2 * count[i];
  rr.runs.resize(std::size_t(rr.offset[nrows]));
  tbb::parallel_for(0, nz, [&](int lz) {
    const int z = rr.lower.z() + lz;
    for (int y = rr.lower.y(); y < rr.lower.y() + ny; ++y) {
      std::int32_t* out = rr.runs.data() + rr.offset[rr.row_index(y, z)];
      scan_row(grid.row(y, z), nx, rr.lower.x(), [&](int b, int e) {
        *out++ = b;
        *out++ = e;
      });
    }
  });
  return rr;
}

/// Kernel rows grouped by plane dz (rows of a plane are consecutive, dy ascending).
struct KernelPlane {
  int dz;
  std::size_t begin, end;
};
std::vector<KernelPlane> kernel_planes(const std::vector<KernelRow>& rows) {
  std::vector<KernelPlane> planes;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (planes.empty() || planes.back().dz != rows[i].dz) planes.push_back({rows[i].dz, i, i});
    planes.back().end = i + 1;
  }
  return planes;
}

/// Sums the moments of B(c, R) ∩ X chord by chord (docs/math.md §7 step 3). With `labels` (one per
/// run), only the runs labelled `label` count: B(c, R) ∩ K for the component K of docs/math.md §7.1.
template <bool Labelled>
BallMoments sweep_ball(const RowRuns& rr, const std::vector<KernelRow>& kernel, const std::vector<KernelPlane>& planes,
                       const Eigen::Vector3i& c, const std::int32_t* labels = nullptr, std::int32_t label = 0) {
  const int ylo = rr.lower.y(), yhi = rr.lower.y() + rr.size.y() - 1;
  const int zlo = rr.lower.z(), zhi = rr.lower.z() + rr.size.z() - 1;
  const std::int32_t* runs = rr.runs.data();
  // The run starting at r is labelled labels[(r - runs) / 2].
  const auto other = [&](const std::int32_t* r) {
    if constexpr (Labelled) return labels[(r - runs) / 2] != label;
    return false;
  };
  std::int64_t m0 = 0, sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  for (const KernelPlane& pl : planes) {
    const int z = c.z() + pl.dz;
    if (z < zlo || z > zhi) continue;
    // Per-plane sums: S0, S1, S2 of the rows and their dy-weighted versions (fewer multiplies).
    std::int64_t P0 = 0, P1 = 0, P2 = 0, Q0 = 0, Q1 = 0, R0 = 0;
    for (std::size_t k = pl.begin; k < pl.end; ++k) {
      const KernelRow& kr = kernel[k];
      const int y = c.y() + kr.dy;
      if (y < ylo || y > yhi) continue;
      const std::size_t ri = rr.row_index(y, z);
      const std::int32_t* r = runs + rr.offset[ri];
      const std::int32_t* rend = runs + rr.offset[ri + 1];
      const int lo = c.x() - kr.w, hi = c.x() + kr.w;
      while (r != rend && r[1] < lo) r += 2;  // skip runs left of the chord
      if (r == rend || r[0] > hi) continue;   // chord entirely outside
      std::int64_t s0, s1, s2;
      if (r[0] <= lo && r[1] >= hi) {
        // Chord entirely inside one run (the common case away from the surface): closed form.
        if (other(r)) continue;
        s0 = 2 * std::int64_t(kr.w) + 1;
        s1 = 0;
        s2 = 2 * G(kr.w);
      } else {
        s0 = s1 = s2 = 0;
        for (; r != rend && r[0] <= hi; r += 2) {
          if (other(r)) continue;
          const std::int64_t p = std::max<int>(r[0], lo) - c.x();
          const std::int64_t q = std::min<int>(r[1], hi) - c.x();
          const std::int64_t n = q - p + 1;
          s0 += n;
          s1 += (p + q) * n / 2;
          s2 += G(q) - G(p - 1);
        }
      }
      const std::int64_t dy = kr.dy;
      P0 += s0;
      P1 += s1;
      P2 += s2;
      Q0 += dy * s0;
      Q1 += dy * s1;
      R0 += dy * dy * s0;
    }
    const std::int64_t dz = pl.dz;
    m0 += P0;
    sx += P1;
    sy += Q0;
    sz += dz * P0;
    xx += P2;
    xy += Q1;
    xz += dz * P1;
    yy += R0;
    yz += dz * Q0;
    zz += dz * dz * P0;
  }
  BallMoments m;
  m.m0 = m0;
  m.m1[0] = sx, m.m1[1] = sy, m.m1[2] = sz;
  m.m2[0] = xx, m.m2[1] = xy, m.m2[2] = xz, m.m2[3] = yy, m.m2[4] = yz, m.m2[5] = zz;
  return m;
}

BallMoments moments_by_rows(const RowRuns& rr, const std::vector<KernelRow>& kernel,
                            const std::vector<KernelPlane>& planes, const Eigen::Vector3i& c) {
  return sweep_ball<false>(rr, kernel, planes, c);
}

/// The 6-components of X (docs/math.md §7.1), one label per run of `rr`, numbered 0, 1, ... in
/// run order: runs join when they share an x on the neighbouring row (y + 1 or z + 1).
std::vector<std::int32_t> label_runs(const RowRuns& rr, std::int32_t& count) {
  const std::size_t nruns = rr.runs.size() / 2;
  std::vector<std::size_t> parent(nruns);
  for (std::size_t i = 0; i < nruns; ++i) parent[i] = i;
  const auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  // Runs of rows a and b (each sorted by x) that share an x are 6-adjacent.
  const auto unite_overlapping = [&](std::size_t a, std::size_t b) {
    std::int64_t i = rr.offset[a], j = rr.offset[b];
    while (i < rr.offset[a + 1] && j < rr.offset[b + 1]) {
      const std::int32_t* p = rr.runs.data() + i;
      const std::int32_t* q = rr.runs.data() + j;
      if (p[0] <= q[1] && q[0] <= p[1]) {
        const std::size_t u = find(std::size_t(i / 2)), v = find(std::size_t(j / 2));
        if (u != v) parent[std::max(u, v)] = std::min(u, v);
      }
      if (p[1] < q[1])
        i += 2;
      else
        j += 2;
    }
  };
  for (int lz = 0; lz < rr.size.z(); ++lz)
    for (int ly = 0; ly < rr.size.y(); ++ly) {
      const int y = rr.lower.y() + ly, z = rr.lower.z() + lz;
      if (ly > 0) unite_overlapping(rr.row_index(y - 1, z), rr.row_index(y, z));
      if (lz > 0) unite_overlapping(rr.row_index(y, z - 1), rr.row_index(y, z));
    }
  std::vector<std::int32_t> label(nruns);
  count = 0;
  for (std::size_t i = 0; i < nruns; ++i) label[i] = parent[i] == i ? count++ : label[find(i)];
  return label;
}

/// The run of `rr` holding voxel v, or -1 when v is outside X.
std::int64_t run_of(const RowRuns& rr, const Eigen::Vector3i& v) {
  if ((v - rr.lower).minCoeff() < 0 || (v - rr.lower - rr.size).maxCoeff() >= 0) return -1;
  const std::size_t ri = rr.row_index(v.y(), v.z());
  for (std::int64_t j = rr.offset[ri]; j < rr.offset[ri + 1]; j += 2)
    if (rr.runs[std::size_t(j)] <= v.x() && v.x() <= rr.runs[std::size_t(j) + 1]) return j / 2;
  return -1;
}

/// The moments of the voxels v of the digital ball B(c, R) (the kernel of docs/math.md §7) for which
/// keep(v) holds, one voxel at a time: the readable sum both brute-force forms share.
template <class Keep>
BallMoments ball_moments_where(const Eigen::Vector3i& c, double digital_radius, double h, Keep keep) {
  const double R = digital_radius * h;
  const int n = int(std::ceil(digital_radius)) + 1;
  BallMoments m;
  for (int dz = -n; dz <= n; ++dz)
    for (int dy = -n; dy <= n; ++dy)
      for (int dx = -n; dx <= n; ++dx) {
        if (!in_kernel(dx, dy, dz, R, h) || !keep(c + Eigen::Vector3i(dx, dy, dz))) continue;
        const std::int64_t d[3] = {dx, dy, dz};
        ++m.m0;
        for (int a = 0; a < 3; ++a) m.m1[a] += d[a];
        m.m2[0] += d[0] * d[0], m.m2[1] += d[0] * d[1], m.m2[2] += d[0] * d[2];
        m.m2[3] += d[1] * d[1], m.m2[4] += d[1] * d[2], m.m2[5] += d[2] * d[2];
      }
  return m;
}

}  // namespace

std::vector<BallMoments> ii_moments_brute_force(const VoxelGrid& grid, double digital_radius, double h,
                                                const std::vector<Eigen::Vector3i>& centres) {
  std::vector<BallMoments> out(centres.size());
  tbb::parallel_for(std::size_t(0), centres.size(), [&](std::size_t i) {
    out[i] = ball_moments_where(centres[i], digital_radius, h,
                                [&](const Eigen::Vector3i& v) { return grid.get(v.x(), v.y(), v.z()); });
  });
  return out;
}

std::vector<BallMoments> ii_component_moments_brute_force(const VoxelGrid& grid, double digital_radius, double h,
                                                          const std::vector<IIBall>& balls) {
  // Each voxel of X gets the number of its 6-component (flood fill); -1 outside X.
  const Eigen::Vector3i lo = grid.lower(), size = grid.size();
  const auto slot = [&](const Eigen::Vector3i& v) {
    const Eigen::Vector3i l = v - lo;
    return (std::size_t(l.z()) * std::size_t(size.y()) + std::size_t(l.y())) * std::size_t(size.x()) +
           std::size_t(l.x());
  };
  std::vector<std::int32_t> component(std::size_t(size.prod()), -1);
  std::int32_t count = 0;
  std::vector<Eigen::Vector3i> stack;
  for (int z = lo.z(); z <= grid.upper().z(); ++z)
    for (int y = lo.y(); y <= grid.upper().y(); ++y)
      for (int x = lo.x(); x <= grid.upper().x(); ++x) {
        if (!grid.get(x, y, z) || component[slot({x, y, z})] >= 0) continue;
        component[slot({x, y, z})] = count;
        stack.push_back({x, y, z});
        while (!stack.empty()) {
          const Eigen::Vector3i v = stack.back();
          stack.pop_back();
          for (int a = 0; a < 3; ++a)
            for (const int s : {-1, 1}) {
              Eigen::Vector3i u = v;
              u[a] += s;
              if (grid.get(u.x(), u.y(), u.z()) && component[slot(u)] < 0) {
                component[slot(u)] = count;
                stack.push_back(u);
              }
            }
        }
        ++count;
      }
  const auto component_of = [&](const Eigen::Vector3i& v) {
    return grid.get(v.x(), v.y(), v.z()) ? component[slot(v)] : -1;
  };
  // The brute-force ball of ii_moments_brute_force over the seed's component.
  std::vector<BallMoments> out(balls.size());
  tbb::parallel_for(std::size_t(0), balls.size(), [&](std::size_t i) {
    const std::int32_t label = component_of(balls[i].seed);
    if (label >= 0)
      out[i] = ball_moments_where(balls[i].centre, digital_radius, h,
                                  [&](const Eigen::Vector3i& v) { return component_of(v) == label; });
  });
  return out;
}

std::vector<BallMoments> ii_moments(const VoxelGrid& grid, double digital_radius, double h,
                                    const std::vector<Eigen::Vector3i>& centres, const ProgressFn& progress) {
  const RowRuns rr = encode_runs(grid);
  const std::vector<KernelRow> kernel = kernel_rows(digital_radius, h);
  const std::vector<KernelPlane> planes = kernel_planes(kernel);
  std::vector<BallMoments> out(centres.size());
  std::atomic<std::int64_t> done{0};
  const std::int64_t total = std::int64_t(centres.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, centres.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                        out[i] = moments_by_rows(rr, kernel, planes, centres[i]);
                      if (progress) progress(done += std::int64_t(range.size()), total);
                    });
  return out;
}

ComponentMoments ii_component_moments(const VoxelGrid& grid, double digital_radius, double h,
                                      const std::vector<IIBall>& balls, const ProgressFn& progress) {
  ComponentMoments out;
  if (balls.size() >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
    throw InputError("II normals: " + std::to_string(balls.size()) + " balls, more than this estimator indexes (" +
                         std::to_string(std::numeric_limits<std::uint32_t>::max()) + "); use a coarser resolution",
                     "resolution");
  out.index.assign(balls.size(), 0);
  if (balls.empty()) return out;
  const RowRuns rr = encode_runs(grid);
  std::int32_t components = 0;
  const std::vector<std::int32_t> labels = label_runs(rr, components);
  // Each ball's component; -1 (zero moments) when its seed is not in X.
  std::vector<std::int32_t> label(balls.size());
  tbb::parallel_for(std::size_t(0), balls.size(), [&](std::size_t i) {
    const Eigen::Vector3i& v = balls[i].seed;
    if (components == 1) {
      label[i] = grid.get(v.x(), v.y(), v.z()) ? 0 : -1;
      return;
    }
    const std::int64_t r = run_of(rr, v);
    label[i] = r < 0 ? -1 : labels[std::size_t(r)];
  });
  // Balls grouped by (centre, component), neighbouring surfels sharing voxels: sorted by the
  // centre's index in the centres' bounding box, then the component.
  Eigen::Vector3i lo = balls[0].centre, hi = lo;
  for (const IIBall& b : balls) lo = lo.cwiseMin(b.centre), hi = hi.cwiseMax(b.centre);
  const Eigen::Matrix<std::int64_t, 3, 1> sz = (hi - lo + Eigen::Vector3i::Ones()).cast<std::int64_t>();
  struct Key {
    std::int64_t centre;
    std::int32_t label;
    std::uint32_t ball;
    bool operator<(const Key& o) const { return centre != o.centre ? centre < o.centre : label < o.label; }
  };
  std::vector<Key> order(balls.size());
  for (std::size_t i = 0; i < balls.size(); ++i) {
    const Eigen::Matrix<std::int64_t, 3, 1> d = (balls[i].centre - lo).cast<std::int64_t>();
    order[i] = {(d.z() * sz.y() + d.y()) * sz.x() + d.x(), label[i], std::uint32_t(i)};
  }
  std::sort(order.begin(), order.end());
  std::vector<std::size_t> group{0};
  for (std::size_t i = 1; i < order.size(); ++i)
    if (order[i].centre != order[i - 1].centre || order[i].label != order[i - 1].label) group.push_back(i);
  group.push_back(order.size());
  const std::size_t groups = group.size() - 1;

  const std::vector<KernelRow> kernel = kernel_rows(digital_radius, h);
  const std::vector<KernelPlane> planes = kernel_planes(kernel);
  // The components' bounding boxes: a ball whose kernel cube meets no other component's box needs
  // no label (the common case for a few objects apart). Many components (noise in a scan) are not
  // worth testing one by one: every ball then reads the labels.
  constexpr std::int32_t kBoxedComponents = 64;
  std::vector<Eigen::AlignedBox3i> box(std::size_t(std::min(components, kBoxedComponents + 1)));
  if (components > 1 && components <= kBoxedComponents)
    for (int lz = 0; lz < rr.size.z(); ++lz)
      for (int ly = 0; ly < rr.size.y(); ++ly) {
        const int y = rr.lower.y() + ly, z = rr.lower.z() + lz;
        const std::size_t ri = rr.row_index(y, z);
        for (std::int64_t j = rr.offset[ri]; j < rr.offset[ri + 1]; j += 2) {
          Eigen::AlignedBox3i& b = box[std::size_t(labels[std::size_t(j / 2)])];
          b.extend(Eigen::Vector3i(rr.runs[std::size_t(j)], y, z));
          b.extend(Eigen::Vector3i(rr.runs[std::size_t(j) + 1], y, z));
        }
      }
  const int reach = int(std::ceil(digital_radius)) + 1;
  const auto alone = [&](const Eigen::Vector3i& c, std::int32_t label) {
    if (components == 1) return true;
    if (components > kBoxedComponents) return false;
    const Eigen::AlignedBox3i cube(c - Eigen::Vector3i::Constant(reach), c + Eigen::Vector3i::Constant(reach));
    for (std::int32_t k = 0; k < components; ++k)
      if (k != label && cube.intersects(box[std::size_t(k)])) return false;
    return true;
  };
  out.moments.resize(groups);
  std::atomic<std::int64_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 256), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      const Key& first = order[group[g]];
      const Eigen::Vector3i& c = balls[first.ball].centre;
      // No other component within reach: every run counts, the sweep of ii_moments.
      if (first.label < 0)
        out.moments[g] = BallMoments{};
      else if (alone(c, first.label))
        out.moments[g] = sweep_ball<false>(rr, kernel, planes, c);
      else
        out.moments[g] = sweep_ball<true>(rr, kernel, planes, c, labels.data(), first.label);
      for (std::size_t j = group[g]; j < group[g + 1]; ++j) out.index[order[j].ball] = std::uint32_t(g);
    }
    if (progress) progress(done += std::int64_t(range.size()), std::int64_t(groups));
  });
  return out;
}

namespace {

// The moments of `balls` at digital radius rd, by `method`.
ComponentMoments moments_by(IIMethod method, const VoxelGrid& grid, double rd, double h,
                            const std::vector<IIBall>& balls, const ProgressFn& progress) {
  if (method == IIMethod::Fast) return ii_component_moments(grid, rd, h, balls, progress);
  ComponentMoments mom;
  mom.moments = ii_component_moments_brute_force(grid, rd, h, balls);
  mom.index.resize(balls.size());
  for (std::size_t i = 0; i < balls.size(); ++i) mom.index[i] = std::uint32_t(i);
  return mom;
}

}  // namespace

IIStartRadius ii_start_radius(double digital_radius, double across, bool shrink_on_thin_parts) {
  // §7.2: an object smaller than the ball is the thinnest of parts; its balls start below its size.
  IIStartRadius start{digital_radius, shrink_on_thin_parts && digital_radius >= across && across > 1.0};
  if (start.smaller_than_ball) start.radius = std::max(1.0, kIIShrinkFactor * across);
  return start;
}

// docs/math.md §7 steps 4 and 5 for one surfel, and §7.2's test of the result.
IIFaceEstimate ii_estimate_from_moments(const BallMoments& inner, const BallMoments& outer,
                                        const Eigen::Vector3d& trivial_normal, const Eigen::Vector3d& around) {
  const Eigen::Matrix3d C = 0.5 * (inner.covariance() + outer.covariance());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  IIFaceEstimate e;
  e.normal = es.eigenvectors().col(0);
  if (e.normal.dot(trivial_normal) < 0.0) e.normal = -e.normal;
  const Eigen::Vector3d lambda = es.eigenvalues();
  static const double min_cosine = std::cos(kIIAmbiguousAngleDeg * std::numbers::pi / 180.0);
  e.ambiguous = !(lambda[0] < kIIAmbiguousEigenRatio * lambda[1]) ||
                (around.squaredNorm() > 0.0 && e.normal.dot(around) < min_cosine);
  return e;
}

Eigen::MatrixX3d ii_trivial_normals_around(const SurfelMesh& mesh) {
  const Eigen::Index F = mesh.num_faces();
  Eigen::MatrixX3d at_vertex = Eigen::MatrixX3d::Zero(mesh.num_vertices(), 3);
  for (Eigen::Index f = 0; f < F; ++f) {
    const Eigen::RowVector3d t = mesh.surfels[std::size_t(f)].trivial_normal().transpose();
    for (int k = 0; k < 4; ++k) at_vertex.row(mesh.faces(f, k)) += t;
  }
  Eigen::MatrixX3d around(F, 3);
  for (Eigen::Index f = 0; f < F; ++f) {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) sum += at_vertex.row(mesh.faces(f, k));
    const double norm = sum.norm();
    around.row(f) = norm > 0.0 ? Eigen::RowVector3d(sum / norm) : Eigen::RowVector3d::Zero();
  }
  return around;
}

void ii_retry_thin_parts(const IIStartRadius& start, const Eigen::MatrixX3d& trivial, const Eigen::MatrixX3d& around,
                         std::vector<std::uint8_t>& ambiguous, Eigen::MatrixX3d& normals,
                         const IIFaceMoments& moments) {
  const std::size_t F = ambiguous.size();
  const auto row = [](const Eigen::MatrixX3d& m, std::size_t f) -> Eigen::Vector3d {
    return m.row(Eigen::Index(f)).transpose();
  };
  for (double r = start.radius; r > 1.0;) {
    r = std::max(1.0, r * kIIShrinkFactor);
    std::vector<std::size_t> again;
    for (std::size_t f = 0; f < F; ++f)
      if (ambiguous[f]) again.push_back(f);
    if (again.empty()) break;
    const std::vector<BallMoments> m = moments(r, again);
    tbb::parallel_for(std::size_t(0), again.size(), [&](std::size_t i) {
      const std::size_t f = again[i];
      const IIFaceEstimate e = ii_estimate_from_moments(m[2 * i], m[2 * i + 1], row(trivial, f), row(around, f));
      if (e.ambiguous) return;
      normals.row(Eigen::Index(f)) = e.normal.transpose();
      ambiguous[f] = 0;
    });
  }
  // Still ambiguous with a one-voxel ball: no ball sees a surface there. Near a cavity of a few
  // voxels or voxels meeting at a corner the first estimate is kept, as without shrinking. On an
  // object smaller than the ball (a speck) every ball sees all of it, and the trivial normals
  // around the face are the only direction there is.
  if (!start.smaller_than_ball) return;
  for (std::size_t f = 0; f < F; ++f) {
    if (!ambiguous[f]) continue;
    const Eigen::Vector3d t = row(trivial, f), a = row(around, f);
    normals.row(Eigen::Index(f)) = (a.dot(t) > 0.0 ? a : t).transpose();
  }
}

Eigen::Vector3d ii_normal_from_moments(const BallMoments& inner, const BallMoments& outer,
                                       const Eigen::Vector3d& trivial_normal) {
  return ii_estimate_from_moments(inner, outer, trivial_normal, Eigen::Vector3d::Zero()).normal;
}

Eigen::MatrixX3d ii_face_normals(const VoxelGrid& grid, const SurfelMesh& mesh, const IIParams& params, IIMethod method,
                                 const ProgressFn& progress) {
  if (!mesh.has_surfels())
    throw InputError(
        "II normals need the voxels of the surface (a surface digitized from a shape or a volume, not a mesh file)",
        "normals");
  const double h = grid.h();
  const bool shrink = params.shrink_on_thin_parts;
  const IIStartRadius start = ii_start_radius(ii_digital_radius(h, params), object_across(mesh, h), shrink);
  const double rd = start.radius;
  check_radius(grid, rd);
  check_radius_fits_object(mesh, h, rd);
  // docs/math.md §7.1: both balls of a surfel keep the 6-component of X of its inner voxel.
  const std::size_t F = mesh.surfels.size();
  std::vector<IIBall> balls(2 * F);
  for (std::size_t f = 0; f < F; ++f) {
    const Eigen::Vector3i inner = mesh.surfels[f].inner_voxel();
    balls[2 * f] = {inner, inner};
    balls[2 * f + 1] = {mesh.surfels[f].outer_voxel(), inner};
  }
  const ComponentMoments mom = moments_by(method, grid, rd, h, balls, progress);
  const Eigen::MatrixX3d around = shrink ? ii_trivial_normals_around(mesh) : Eigen::MatrixX3d();
  const auto around_of = [&](std::size_t f) -> Eigen::Vector3d {
    return shrink ? Eigen::Vector3d(around.row(Eigen::Index(f)).transpose()) : Eigen::Vector3d::Zero();
  };
  Eigen::MatrixX3d normals(Eigen::Index(F), 3);
  std::vector<std::uint8_t> ambiguous(F, 0);
  tbb::parallel_for(std::size_t(0), F, [&](std::size_t f) {
    const IIFaceEstimate e =
        ii_estimate_from_moments(mom[2 * f], mom[2 * f + 1], mesh.surfels[f].trivial_normal(), around_of(f));
    normals.row(Eigen::Index(f)) = e.normal.transpose();
    ambiguous[f] = e.ambiguous ? 1 : 0;
  });
  if (!shrink) return normals;
  Eigen::MatrixX3d trivial(Eigen::Index(F), 3);
  for (std::size_t f = 0; f < F; ++f) trivial.row(Eigen::Index(f)) = mesh.surfels[f].trivial_normal().transpose();
  ii_retry_thin_parts(start, trivial, around, ambiguous, normals, [&](double r, const std::vector<std::size_t>& faces) {
    std::vector<IIBall> retry(2 * faces.size());
    for (std::size_t i = 0; i < faces.size(); ++i) {
      retry[2 * i] = balls[2 * faces[i]];
      retry[2 * i + 1] = balls[2 * faces[i] + 1];
    }
    const ComponentMoments m = moments_by(method, grid, r, h, retry, {});
    std::vector<BallMoments> out(retry.size());
    for (std::size_t i = 0; i < retry.size(); ++i) out[i] = m[i];
    return out;
  });
  return normals;
}

Eigen::MatrixX3d ii_vertex_normals(const VoxelGrid& grid, const SurfelMesh& mesh, const IIParams& params,
                                   const ProgressFn& progress) {
  const Eigen::MatrixX3d fn = ii_face_normals(grid, mesh, params, IIMethod::Fast, progress);
  return vertex_normals_from_face_normals(fn, mesh.faces, mesh.num_vertices());
}

}  // namespace corrlap

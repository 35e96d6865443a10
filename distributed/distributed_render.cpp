#include "distributed_render.hpp"

#include <mpi.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "distributed_mesh_output.hpp"

namespace corrlap {

namespace {

// Doubles as unsigned integers in the same order (-inf first, +inf last; no NaN here).
std::uint64_t ordered(double x) {
  const auto bits = std::bit_cast<std::uint64_t>(x);
  return (bits >> 63) ? ~bits : bits | (std::uint64_t(1) << 63);
}
double from_ordered(std::uint64_t u) { return std::bit_cast<double>((u >> 63) ? u & ~(std::uint64_t(1) << 63) : ~u); }

// The value of rank k (from 0) in increasing order among every rank's `sorted` values: the smallest
// x with at least k + 1 values <= x over the ranks, bisected on the ordered bits (at most 64 rounds).
double order_statistic(const std::vector<double>& sorted, std::int64_t k) {
  std::uint64_t lo = sorted.empty() ? std::numeric_limits<std::uint64_t>::max() : ordered(sorted.front());
  std::uint64_t hi = sorted.empty() ? 0 : ordered(sorted.back());
  MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
  while (lo < hi) {
    const std::uint64_t mid = lo + (hi - lo) / 2;
    const double x = from_ordered(mid);
    std::int64_t count = std::upper_bound(sorted.begin(), sorted.end(), x) - sorted.begin();
    MPI_Allreduce(MPI_IN_PLACE, &count, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    if (count >= k + 1)
      hi = mid;
    else
      lo = mid + 1;
  }
  return from_ordered(lo);
}

// One sample as it travels between ranks.
struct PackedSample {
  double depth;
  std::int64_t face;
  float colour[3];
  float unused;
};

// MPI's reduction of packed samples: the nearer one, at equal depth the lower face id (as merge_samples).
void nearer(void* in, void* inout, int* count, MPI_Datatype*) {
  const auto* a = static_cast<const PackedSample*>(in);
  auto* b = static_cast<PackedSample*>(inout);
  for (int i = 0; i < *count; ++i)
    if (a[i].depth > b[i].depth || (a[i].depth == b[i].depth && a[i].face < b[i].face)) b[i] = a[i];
}

}  // namespace

FieldPercentiles distributed_field_percentiles(const DistributedSurface& s, const std::string& name,
                                               const Eigen::VectorXd& owned_values) {
  if (owned_values.size() != s.num_owned)
    throw InputError("render: scalar '" + name + "' needs one value per owned vertex");
  std::int64_t bad = std::numeric_limits<std::int64_t>::max();
  for (int v = 0; v < s.num_owned; ++v)
    if (!std::isfinite(owned_values[v])) bad = std::min(bad, s.vertex_ids[std::size_t(v)]);
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
  if (bad != std::numeric_limits<std::int64_t>::max())
    throw InputError("render: scalar '" + name + "' is not finite at vertex " + std::to_string(bad));
  if (s.num_vertices == 0) throw InputError("render: scalar '" + name + "' has no value");
  std::vector<double> sorted(owned_values.data(), owned_values.data() + owned_values.size());
  std::sort(sorted.begin(), sorted.end());
  const auto rank_of = [&](double q) { return std::int64_t(std::floor(q * double(s.num_vertices - 1))); };
  FieldPercentiles p;
  p.low = order_statistic(sorted, rank_of(0.02));
  p.high = order_statistic(sorted, rank_of(0.98));
  for (double& v : sorted) v = std::abs(v);
  std::sort(sorted.begin(), sorted.end());
  p.magnitude_high = order_statistic(sorted, rank_of(0.98));
  return p;
}

Image distributed_render(const DistributedSurface& s, const Eigen::MatrixX3d& positions, const std::string& name,
                         const Eigen::VectorXd& values, const std::optional<ColourScale>& scale,
                         const RenderOptions& options) {
  if (positions.rows() != s.num_owned) throw InputError("render: expected one position per owned vertex");
  // Coloured by the scale's presence: a rank without vertices has no value to show it.
  const bool coloured = scale.has_value();
  if (coloured && values.size() != s.num_owned)
    throw InputError("render: a coloured surface needs one value per owned vertex");
  int finite = positions.allFinite() ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &finite, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (!finite) throw InputError("render: the mesh has a non-finite vertex position");
  if (s.num_faces == 0) throw InputError("render: the mesh has no face");

  // The frame of the whole surface.
  ScreenExtent e = screen_extent(positions, options);
  if (s.num_owned == 0) {
    e.lo_x = e.lo_y = std::numeric_limits<double>::infinity();
    e.hi_x = e.hi_y = -std::numeric_limits<double>::infinity();
  }
  double lows[2] = {e.lo_x, e.lo_y}, highs[2] = {e.hi_x, e.hi_y};
  MPI_Allreduce(MPI_IN_PLACE, lows, 2, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, highs, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  e = {lows[0], highs[0], lows[1], highs[1]};

  // This rank's faces, with their corners' positions and values from their owners.
  PolygonMesh mesh = to_polygon_mesh([&] {
    SurfelMesh m;
    m.faces = s.mesh.faces;
    m.positions = local_rows(s, positions);
    return m;
  }());
  std::optional<ScalarField> field;
  if (coloured) field = ScalarField{name, local_rows(s, values), false};
  RenderSamples samples = render_samples(mesh, field ? &*field : nullptr, scale, e, options, s.face_ids);

  // Merged towards rank 0 in chunks of packed samples.
  MPI_Datatype type;
  MPI_Type_contiguous(int(sizeof(PackedSample)), MPI_BYTE, &type);
  MPI_Type_commit(&type);
  MPI_Op op;
  MPI_Op_create(&nearer, 1, &op);
  const std::size_t n = samples.depth.size(), chunk = std::size_t(1) << 20;
  std::vector<PackedSample> mine(std::min(n, chunk)), merged(s.rank == 0 ? mine.size() : 0);
  for (std::size_t first = 0; first < n; first += chunk) {
    const std::size_t count = std::min(chunk, n - first);
    for (std::size_t i = 0; i < count; ++i) {
      PackedSample& p = mine[i];
      p.depth = samples.depth[first + i];
      p.face = samples.face[first + i];
      std::memcpy(p.colour, &samples.colour[3 * (first + i)], sizeof p.colour);
      p.unused = 0.0f;
    }
    MPI_Reduce(mine.data(), merged.data(), int(count), type, op, 0, MPI_COMM_WORLD);
    if (s.rank != 0) continue;
    for (std::size_t i = 0; i < count; ++i) {
      samples.depth[first + i] = merged[i].depth;
      samples.face[first + i] = merged[i].face;
      std::memcpy(&samples.colour[3 * (first + i)], merged[i].colour, sizeof merged[i].colour);
    }
  }
  MPI_Op_free(&op);
  MPI_Type_free(&type);
  if (s.rank != 0) return Image();
  return render_picture(samples, scale, name, options);
}

}  // namespace corrlap

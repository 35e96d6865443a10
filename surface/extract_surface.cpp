#include "extract_surface.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <ctime>
#include <sstream>

#include "surfel_order.hpp"

namespace corrlap {

namespace {

constexpr int kBits = 21;
// Peak bytes per surfel of extract_surface beyond the grid: the mesh (surfel 20, face 16, about one
// vertex 24), the sort keys (16), corner occurrences and vertex numbering (about 40). Measured: the
// peak RSS of `corrlap digitize` grows by 140 B per surfel (bench/RESULTS.md, "memory budget"), which
// also counts the touched grid pages and the writer; checked before the mesh is allocated.
constexpr double kExtractionBytesPerSurfel = 140.0;
constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;

// Surfel key (docs/math.md §1.4): positive flag, then Khalimsky coordinates relative to the box
// (kc - 2 lower, all in [0, 2n]). Ascending keys = the reference's face order.
inline std::uint64_t surfel_key(std::uint64_t positive, std::uint64_t kx, std::uint64_t ky, std::uint64_t kz) {
  return (positive << 63) | (kx << 42) | (ky << 21) | kz;
}

// Appends, in "y-major" order, the keys of all surfels whose lower voxel has local y in [y0, y1):
// for each y, first (pass A) the axis-0 and axis-2 surfels of the rows (y, z), z ascending, then
// (pass B) the axis-1 surfels between rows (y, z) and (y+1, z), z ascending.
// Why this order: among surfels with equal (positive, kc_x) it is exactly ascending (kc_y, kc_z)
// (axis-2 surfels of row y have kc_y = 2y+1, axis-1 surfels kc_y = 2y+2, axis-0 surfels have their
// own even kc_x), so a stable bucket sort by (positive, kc_x) yields the face order of docs/math.md §1.4.
// Row (y, z) of the grid: all voxels outside, all inside, or mixed. Two equal uniform rows have
// no surfel between them, and a uniform row has none inside it: the scan skips them.
enum RowState : std::uint8_t { kEmptyRow = 0, kFullRow = 1, kMixedRow = 2 };

std::vector<std::uint8_t> row_states(const VoxelGrid& g) {
  const Eigen::Vector3i lo = g.lower(), n = g.size();
  const std::size_t W = g.words_per_row();
  const int rem = n.x() % 64;
  const std::uint64_t last_mask = rem == 0 ? ~std::uint64_t{0} : (std::uint64_t{1} << rem) - 1;
  std::vector<std::uint8_t> state(std::size_t(n.y()) * std::size_t(n.z()));
  tbb::parallel_for(0, n.z(), [&](int lz) {
    for (int ly = 0; ly < n.y(); ++ly) {
      const std::uint64_t* r = g.row(lo.y() + ly, lo.z() + lz);
      std::uint64_t any = 0, all = ~std::uint64_t{0};
      for (std::size_t w = 0; w + 1 < W; ++w) {
        any |= r[w];
        all &= r[w];
      }
      const std::uint64_t last = r[W - 1] & last_mask;
      any |= last;
      all &= last | ~last_mask;
      state[std::size_t(lz) * std::size_t(n.y()) + std::size_t(ly)] =
          any == 0 ? kEmptyRow : (all == ~std::uint64_t{0} ? kFullRow : kMixedRow);
    }
  });
  return state;
}

void scan_rows(const VoxelGrid& g, const std::vector<std::uint8_t>& state, int y0, int y1,
               std::vector<std::uint64_t>& out) {
  auto st = [&](int ly, int lz) { return state[std::size_t(lz) * std::size_t(g.size().y()) + std::size_t(ly)]; };
  const Eigen::Vector3i lo = g.lower(), n = g.size();
  const std::size_t W = g.words_per_row();
  const int rem = n.x() % 64;
  const std::uint64_t last_mask = rem == 0 ? ~std::uint64_t{0} : (std::uint64_t{1} << rem) - 1;
  // axis 0 pairs (x, x+1) need x + 1 < n.x(): valid bits of the last word
  // (only the last word can hold invalid bits: its largest valid x is n.x() - 2 - 64 (W - 1) <= 62)
  const long last_valid0 = long(n.x()) - 2 - 64 * (long(W) - 1);
  const std::uint64_t last_mask0 = last_valid0 < 0 ? 0 : (std::uint64_t{2} << last_valid0) - 1;
  for (int ly = y0; ly < y1; ++ly) {
    const int y = lo.y() + ly;
    for (int lz = 0; lz < n.z(); ++lz) {
      const std::uint8_t here = st(ly, lz);
      if (here != kMixedRow && (lz + 1 == n.z() || st(ly, lz + 1) == here)) continue;
      const std::uint64_t* r = g.row(y, lo.z() + lz);
      const std::uint64_t* s = lz + 1 < n.z() ? g.row(y, lo.z() + lz + 1) : nullptr;
      for (std::size_t w = 0; w < W; ++w) {
        const bool last = w + 1 == W;
        const std::uint64_t a = last ? r[w] & last_mask : r[w];
        const std::uint64_t next = last ? 0 : r[w + 1];
        std::uint64_t t0 = a ^ ((a >> 1) | (next << 63));
        if (last) t0 &= last_mask0;
        std::uint64_t t2 = 0;
        if (s) t2 = (a ^ s[w]) & (last ? last_mask : ~std::uint64_t{0});
        // Both kinds, x ascending; order between different kc_x does not matter (bucketed later).
        while (t0) {
          const int b = std::countr_zero(t0);
          t0 &= t0 - 1;
          const std::uint64_t lx = w * 64 + std::uint64_t(b);
          const std::uint64_t inside = (a >> b) & 1u;  // lower voxel inside: outward +e0, negative
          out.push_back(surfel_key(inside ^ 1u, 2 * lx + 2, 2 * std::uint64_t(ly) + 1, 2 * std::uint64_t(lz) + 1));
        }
        while (t2) {
          const int b = std::countr_zero(t2);
          t2 &= t2 - 1;
          const std::uint64_t lx = w * 64 + std::uint64_t(b);
          const std::uint64_t inside = (a >> b) & 1u;  // outward +e2: negative
          out.push_back(surfel_key(inside ^ 1u, 2 * lx + 1, 2 * std::uint64_t(ly) + 1, 2 * std::uint64_t(lz) + 2));
        }
      }
    }
    if (ly + 1 >= n.y()) continue;
    for (int lz = 0; lz < n.z(); ++lz) {
      const std::uint8_t here = st(ly, lz);
      if (here != kMixedRow && st(ly + 1, lz) == here) continue;
      const std::uint64_t* r = g.row(y, lo.z() + lz);
      const std::uint64_t* s = g.row(y + 1, lo.z() + lz);
      for (std::size_t w = 0; w < W; ++w) {
        std::uint64_t t1 = r[w] ^ s[w];
        if (w + 1 == W) t1 &= last_mask;
        while (t1) {
          const int b = std::countr_zero(t1);
          t1 &= t1 - 1;
          const std::uint64_t lx = w * 64 + std::uint64_t(b);
          const std::uint64_t inside = (r[w] >> b) & 1u;  // outward +e1: positive
          out.push_back(surfel_key(inside, 2 * lx + 1, 2 * std::uint64_t(ly) + 2, 2 * std::uint64_t(lz) + 1));
        }
      }
    }
  }
}

struct DecodedFace {
  int kc[3];
  int axis;
  bool positive;
};
inline DecodedFace decode(std::uint64_t key) {
  DecodedFace d;
  d.positive = key >> 63;
  d.kc[0] = int((key >> 42) & kMask);
  d.kc[1] = int((key >> 21) & kMask);
  d.kc[2] = int(key & kMask);
  d.axis = (d.kc[0] % 2 == 0) ? 0 : (d.kc[1] % 2 == 0 ? 1 : 2);  // the even coordinate
  return d;
}
inline Surfel surfel_of(const DecodedFace& d, const Eigen::Vector3i& lo) {
  Surfel s;
  s.axis = d.axis;
  s.outward = (d.axis == 1) == d.positive ? 1 : -1;
  // kc_rel = 2 (z - lo) + e_k + 1
  for (int a = 0; a < 3; ++a) s.lower_voxel[a] = (d.kc[a] - (a == d.axis ? 2 : 1)) / 2 + lo[a];
  return s;
}
// Relative pointel (Khalimsky / 2) of corner c of the face (docs/math.md §1.4): base order
// B = [(i-,j-),(i-,j+),(i+,j+),(i+,j-)], reversed for negative surfels.
inline void corner_pointel(const DecodedFace& d, int c, int q[3]) {
  static constexpr int si[4] = {-1, -1, +1, +1}, sj[4] = {-1, +1, +1, -1};
  const int i = d.axis == 0 ? 1 : 0, j = d.axis == 2 ? 1 : 2;
  const int b = d.positive ? c : 3 - c;
  int p[3] = {d.kc[0], d.kc[1], d.kc[2]};
  p[i] += si[b];
  p[j] += sj[b];
  q[0] = p[0] / 2;
  q[1] = p[1] / 2;
  q[2] = p[2] / 2;
}

// Manifold sheets (docs/math.md §1.4). Pointels are shared by position, so where voxels touch
// only along an edge or at a corner the quad mesh is pinched: a linel with four surfels, or a pointel
// whose surfels form several fans. The pass below splits those pointels into one vertex per sheet.
//
// Pointel Q is the corner shared by the voxels Q - 1 + d, d in {0,1}^3 (its "cube", bit
// d.x + 2 d.y + 4 d.z of a configuration). The linel from Q along +k (-k) is surrounded by the four
// cube voxels with d_k = 1 (0); a surfel of the cube (two voxels differing along one axis, one
// inside) touches the two linels of the other axes on its side.

// Whether the faces at a pointel with this cube configuration need the pass: some linel has four
// surfels (inside voxels on one diagonal of its square), or the surfels form several fans.
std::array<bool, 256> pointel_needs_split_table() {
  std::array<bool, 256> table{};
  for (int config = 0; config < 256; ++config) {
    auto in = [&](int d) { return (config >> d) & 1; };
    // Surfels of the cube: (voxel bit, axis) with the voxel's d_axis = 0 and a change along axis.
    std::vector<std::pair<int, int>> surfels;
    for (int d = 0; d < 8; ++d)
      for (int a = 0; a < 3; ++a)
        if (!((d >> a) & 1) && in(d) != in(d | (1 << a))) surfels.push_back({d, a});
    const int n = int(surfels.size());
    std::vector<int> parent(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) parent[std::size_t(i)] = i;
    auto find = [&](int i) {
      while (parent[std::size_t(i)] != i) i = parent[std::size_t(i)];
      return i;
    };
    bool diagonal = false;
    for (int k = 0; k < 3; ++k)
      for (int side = 0; side < 2; ++side) {
        // The linel (k, side): its surfels have both voxels with d_k = side, and axis != k.
        std::vector<int> at;
        for (int i = 0; i < n; ++i)
          if (surfels[std::size_t(i)].second != k && ((surfels[std::size_t(i)].first >> k) & 1) == side)
            at.push_back(i);
        if (at.size() == 4) diagonal = true;
        if (at.size() == 2) parent[std::size_t(find(at[0]))] = find(at[1]);
      }
    int fans = 0;
    for (int i = 0; i < n; ++i) fans += find(i) == i;
    table[std::size_t(config)] = diagonal || fans > 1;
  }
  return table;
}

// Whether split_pinched_pointels looks at pointel q: a pinched configuration of its cube, or a
// pointel on the box's faces, where the surfels toward voxels outside the box do not exist.
bool pointel_flagged(const VoxelGrid& grid, const Eigen::Vector3i& q) {
  static const std::array<bool, 256> needs = pointel_needs_split_table();
  if ((q.array() - 1 < grid.lower().array()).any() || (q.array() > grid.upper().array()).any()) return true;
  int config = 0;
  for (int d = 0; d < 8; ++d)
    if (grid.get(q.x() - 1 + (d & 1), q.y() - 1 + ((d >> 1) & 1), q.z() - 1 + ((d >> 2) & 1))) config |= 1 << d;
  return needs[std::size_t(config)];
}

// Splits every pinched pointel of `mesh` (extracted from `grid`) into one vertex per sheet: faces
// around a vertex that share a linel stay together, and at a linel with four surfels they pair up
// toward the inside voxel (interior adjacency: inside voxels touching along an edge only are apart).
// The one exception: when the two inside voxels at the linel are face-connected around it at both
// of its ends (within each end's cube), interior pairing would leave both sheets with the same two
// end vertices (an edge of four faces again), so there the surfels pair toward the outside voxel.
// Both ends decide by the same cubes, so they agree. New vertices are appended in order (original
// vertex, then the smallest face of the sheet), so that manifold surfaces keep the reference numbering.
void split_pinched_pointels(const VoxelGrid& grid, SurfelMesh& mesh) {
  const double h = grid.h();
  const int V = mesh.num_vertices(), F = mesh.num_faces();
  auto pointel = [&](int v) {
    Eigen::Vector3i q;
    for (int a = 0; a < 3; ++a) q[a] = int(std::lround(mesh.positions(v, a) / h + 0.5));
    return q;
  };
  auto in = [&](const Eigen::Vector3i& x) { return grid.get(x.x(), x.y(), x.z()); };
  // 1. Flag the pointels that need the pass (pinched configurations, and the box's faces, where the
  //    surfels toward voxels outside the box do not exist).
  std::vector<std::uint8_t> flagged(std::size_t(V), 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v != r.end(); ++v) {
      flagged[std::size_t(v)] = pointel_flagged(grid, pointel(v));
    }
  });
  // 2. Faces at the flagged vertices, by vertex then face.
  std::vector<std::pair<int, int>> incidence;  // (vertex, 4 face + corner)
  for (int f = 0; f < F; ++f)
    for (int c = 0; c < 4; ++c)
      if (flagged[std::size_t(mesh.faces(f, c))]) incidence.push_back({mesh.faces(f, c), 4 * f + c});
  if (incidence.empty()) return;
  std::stable_sort(incidence.begin(), incidence.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // 3. Sheets of each flagged vertex; corners of the second and later sheets get new vertices.
  std::vector<std::pair<int, int>> renumber;  // (4 face + corner, new vertex)
  std::vector<int> copies_of;                 // original vertex of each new vertex
  for (std::size_t b = 0; b < incidence.size();) {
    std::size_t e = b;
    while (e < incidence.size() && incidence[e].first == incidence[b].first) ++e;
    const int v = incidence[b].first, n = int(e - b);
    const Eigen::Vector3i qv = pointel(v);
    std::vector<int> parent(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) parent[std::size_t(i)] = i;
    auto find = [&](int i) {
      while (parent[std::size_t(i)] != i) i = parent[std::size_t(i)];
      return i;
    };
    // The faces along each linel (v, w), w a neighbour of v in a face.
    std::vector<std::pair<int, int>> along;  // (w, local face index)
    for (int i = 0; i < n; ++i) {
      const int f = incidence[b + std::size_t(i)].second / 4, c = incidence[b + std::size_t(i)].second % 4;
      along.push_back({mesh.faces(f, (c + 1) % 4), i});
      along.push_back({mesh.faces(f, (c + 3) % 4), i});
    }
    std::sort(along.begin(), along.end());
    for (std::size_t s = 0; s < along.size();) {
      std::size_t t = s;
      while (t < along.size() && along[t].first == along[s].first) ++t;
      auto face_of = [&](std::size_t k) { return incidence[b + std::size_t(along[k].second)].second / 4; };
      if (t - s == 2) {
        parent[std::size_t(find(along[s].second))] = find(along[s + 1].second);
      } else if (t - s == 4) {
        // Inside voxels A, B (diagonal) and outside ones around the linel; dir from v to w.
        const Eigen::Vector3i dir = pointel(along[s].first) - qv;
        std::vector<Eigen::Vector3i> inside, outside;
        for (std::size_t k = s; k < t; ++k) {
          const Surfel& sf = mesh.surfels[std::size_t(face_of(k))];
          for (const Eigen::Vector3i& x : {sf.inner_voxel(), sf.outer_voxel()}) {
            auto& list = in(x) ? inside : outside;
            if (std::find(list.begin(), list.end(), x) == list.end()) list.push_back(x);
          }
        }
        // A and B face-connected within the cube at the end `sign` (the layer beyond that end).
        auto joined = [&](int sign) {
          const Eigen::Vector3i off = sign * dir;
          return in(inside[0] + off) && in(inside[1] + off) && (in(outside[0] + off) || in(outside[1] + off));
        };
        const bool toward_outside = inside.size() == 2 && outside.size() == 2 && joined(-1) && joined(+1);
        for (std::size_t k = s; k < t; ++k)
          for (std::size_t l = k + 1; l < t; ++l) {
            const Surfel& a = mesh.surfels[std::size_t(face_of(k))];
            const Surfel& c = mesh.surfels[std::size_t(face_of(l))];
            const bool pair = toward_outside ? a.outer_voxel() == c.outer_voxel() : a.inner_voxel() == c.inner_voxel();
            if (pair) parent[std::size_t(find(along[k].second))] = find(along[l].second);
          }
      }
      s = t;
    }
    // Sheets in order of their smallest face; the first keeps v.
    std::vector<int> sheet_vertex(std::size_t(n), -1);
    bool first = true;
    for (int i = 0; i < n; ++i) {
      const int root = find(i);
      if (sheet_vertex[std::size_t(root)] < 0) {
        sheet_vertex[std::size_t(root)] = first ? v : V + int(copies_of.size());
        if (!first) copies_of.push_back(v);
        first = false;
      }
      if (sheet_vertex[std::size_t(root)] != v)
        renumber.push_back({incidence[b + std::size_t(i)].second, sheet_vertex[std::size_t(root)]});
    }
    b = e;
  }
  if (copies_of.empty()) return;
  for (const auto& [corner, id] : renumber) mesh.faces(corner / 4, corner % 4) = id;
  mesh.positions.conservativeResize(Eigen::Index(V + int(copies_of.size())), 3);
  for (std::size_t i = 0; i < copies_of.size(); ++i)
    mesh.positions.row(V + Eigen::Index(i)) = mesh.positions.row(copies_of[i]);
}

// Steps 1 and 2 of extract_surface: the surfel keys in face order, and where each bucket
// (positive, kc_x) starts. `check_count` sees the number of surfels before the sort allocates.
struct SortedKeys {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> bucket_start;  // 2 (2 n_x + 2) + 1 entries
};
template <class CheckCount, class Lap>
SortedKeys sorted_surfel_keys(const VoxelGrid& grid, CheckCount check_count, Lap lap) {
  const Eigen::Vector3i n = grid.size();
  // 1. Surfel keys of chunks of y rows, in parallel (docs/math.md §1.3).
  const int chunks = std::min(n.y(), 64);
  std::vector<std::vector<std::uint64_t>> chunk_keys(std::size_t(chunks), std::vector<std::uint64_t>{});
  auto chunk_begin = [&](int c) { return int((std::int64_t(n.y()) * c) / chunks); };
  const std::vector<std::uint8_t> states = row_states(grid);
  tbb::parallel_for(0, chunks, [&](int c) {
    scan_rows(grid, states, chunk_begin(c), chunk_begin(c + 1), chunk_keys[std::size_t(c)]);
  });
  std::size_t F = 0;
  for (const auto& v : chunk_keys) F += v.size();
  check_count(F);
  lap("transitions");

  // 2. Face order (docs/math.md §1.4): stable counting sort by bucket (positive, kc_x); within a bucket the
  //    chunks are in y order and each chunk is already in (kc_y, kc_z) order (see scan_rows).
  const std::size_t NKX = 2 * std::size_t(n.x()) + 2, NB = 2 * NKX;
  auto bucket = [&](std::uint64_t key) { return std::size_t(key >> 63) * NKX + std::size_t((key >> 42) & kMask); };
  std::vector<std::uint32_t> counts(std::size_t(chunks) * NB, 0);
  tbb::parallel_for(0, chunks, [&](int c) {
    std::uint32_t* cnt = counts.data() + std::size_t(c) * NB;
    for (std::uint64_t k : chunk_keys[std::size_t(c)]) ++cnt[bucket(k)];
  });
  SortedKeys out;
  std::vector<std::uint32_t>& bucket_start = out.bucket_start;
  bucket_start.resize(NB + 1);
  {
    std::uint32_t run = 0;
    for (std::size_t b = 0; b < NB; ++b) {
      bucket_start[b] = run;
      for (int c = 0; c < chunks; ++c) {
        std::uint32_t& x = counts[std::size_t(c) * NB + b];
        const std::uint32_t k = x;
        x = run;  // becomes the chunk's write offset in bucket b
        run += k;
      }
    }
    bucket_start[NB] = run;
  }
  std::vector<std::uint64_t>& keys = out.keys;
  keys.resize(F);
  tbb::parallel_for(0, chunks, [&](int c) {
    std::uint32_t* off = counts.data() + std::size_t(c) * NB;
    for (std::uint64_t k : chunk_keys[std::size_t(c)]) keys[off[bucket(k)]++] = k;
    std::vector<std::uint64_t>().swap(chunk_keys[std::size_t(c)]);
  });
  std::vector<std::uint32_t>().swap(counts);
  lap("face order");
  return out;
}

}  // namespace

SurfelMesh extract_surface(const VoxelGrid& grid) { return extract_surface(grid, nullptr); }

SurfelMesh extract_surface(const VoxelGrid& grid, PhaseTimings* timings) {
  auto cpu_now = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
  };
  Stopwatch wall;
  double c0 = timings ? cpu_now() : 0.0;
  auto lap = [&](const char* name) {
    if (!timings) return;
    const double w = wall.lap();
    const double c1 = cpu_now();
    timings->phases.push_back({name, w, c1 - c0});
    c0 = c1;
  };
  if (grid.empty_box()) throw InputError("surface extraction: the voxel grid has no voxels");
  const Eigen::Vector3i lo = grid.lower(), n = grid.size();
  if ((n.array() * 2 + 4 >= (1 << kBits)).any())
    throw InputError("surface extraction: the box is too large (more than 1M voxels along an axis)");

  const std::size_t NKX = 2 * std::size_t(n.x()) + 2;
  SortedKeys sorted = sorted_surfel_keys(
      grid,
      [&](std::size_t F) {
        if (F == 0)
          throw InputError(
              "surface extraction: the volume has no surfel (it is empty, full, or touches no voxel pair inside the "
              "box)");
        // Corner occurrences 4 f + c must fit in 32 bits with one value left as the "none" marker.
        if (F >= (std::size_t{1} << 30)) throw InputError("surface extraction: 2^30 or more surfels");
        // The mesh and the extraction's own arrays, before they are allocated: at most
        // kExtractionBytesPerSurfel per surfel (bench/RESULTS.md, "memory budget").
        check_memory_budget(double(F) * kExtractionBytesPerSurfel + double(grid.memory_bytes()),
                            "surface extraction of " + std::to_string(F) + " surfels",
                            "use a larger grid step h or a smaller box");
      },
      lap);
  const std::vector<std::uint64_t>& keys = sorted.keys;
  const std::vector<std::uint32_t>& bucket_start = sorted.bucket_start;
  const std::size_t F = keys.size();

  SurfelMesh mesh;
  mesh.h = grid.h();
  mesh.surfels.resize(F);
  mesh.faces.resize(Eigen::Index(F), 4);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f != r.end(); ++f) {
      mesh.surfels[f] = surfel_of(decode(keys[f]), lo);
    }
  });
  lap("surfels");

  // 3. Vertices numbered by first appearance (docs/math.md §1.4). A pointel with relative x index P is
  //    a corner only of faces with kc_x in {2P-1, 2P, 2P+1}: per class a contiguous range of
  //    faces. Each pointel slab P is handled by one task with a dense (y, z) table of first
  //    occurrences, visiting the corners in increasing occurrence order 4 f + c.
  //    faces() temporarily holds each corner's first occurrence; is_new marks first occurrences.
  const std::size_t NYZ = std::size_t(n.y() + 1) * std::size_t(n.z() + 1);
  constexpr std::uint32_t kNone = ~std::uint32_t{0};
  std::vector<std::uint8_t> is_new(4 * F, 0);
  std::uint32_t* raw = reinterpret_cast<std::uint32_t*>(mesh.faces.data());
  tbb::enumerable_thread_specific<std::vector<std::uint32_t>> tables(
      [&] { return std::vector<std::uint32_t>(NYZ, kNone); });
  tbb::enumerable_thread_specific<std::vector<std::uint32_t>> touched_lists;
  tbb::parallel_for(0, n.x() + 1, [&](int P) {
    std::vector<std::uint32_t>& first = tables.local();
    std::vector<std::uint32_t>& touched = touched_lists.local();
    touched.clear();
    for (std::size_t cls = 0; cls < 2; ++cls) {
      const std::size_t b0 = cls * NKX + std::size_t(std::max(0, 2 * P - 1)), b1 = cls * NKX + std::size_t(2 * P + 2);
      for (std::size_t f = bucket_start[b0]; f < bucket_start[b1]; ++f) {
        const DecodedFace d = decode(keys[f]);
        for (int c = 0; c < 4; ++c) {
          int q[3];
          corner_pointel(d, c, q);
          if (q[0] != P) continue;
          const std::size_t idx = std::size_t(q[1]) * std::size_t(n.z() + 1) + std::size_t(q[2]);
          const std::uint32_t o = std::uint32_t(4 * f + std::size_t(c));
          if (first[idx] == kNone) {
            first[idx] = o;
            is_new[o] = 1;
            touched.push_back(std::uint32_t(idx));
          }
          raw[o] = first[idx];
        }
      }
    }
    for (std::uint32_t idx : touched) first[idx] = kNone;
  });
  lap("first occurrences");

  // Vertex id of a first occurrence = number of first occurrences before it.
  std::vector<std::uint32_t> base(F + 1);
  {
    std::uint32_t run = 0;
    for (std::size_t f = 0; f < F; ++f) {
      base[f] = run;
      run += std::uint32_t(is_new[4 * f] + is_new[4 * f + 1] + is_new[4 * f + 2] + is_new[4 * f + 3]);
    }
    base[F] = run;
  }
  const std::size_t V = base[F];
  mesh.positions.resize(Eigen::Index(V), 3);
  const double h = grid.h();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f != r.end(); ++f) {
      DecodedFace d;
      bool decoded = false;
      for (int c = 0; c < 4; ++c) {
        const std::uint32_t o = raw[4 * f + std::size_t(c)];
        const std::size_t g = o / 4;
        std::uint32_t id = base[g];
        for (std::uint32_t k = 0; k < o % 4; ++k) id += is_new[4 * g + k];
        mesh.faces(Eigen::Index(f), c) = int(id);
        if (is_new[4 * f + std::size_t(c)]) {
          if (!decoded) d = decode(keys[f]), decoded = true;
          int q[3];
          corner_pointel(d, c, q);
          // pointel relative index q -> Khalimsky 2(q + lo); corner in grid units = (kc - 1) / 2
          for (int a = 0; a < 3; ++a) mesh.positions(Eigen::Index(id), a) = pointel_coordinate(q[a] + lo[a], h);
        }
      }
    }
  });
  lap("faces+positions");
  split_pinched_pointels(grid, mesh);
  lap("manifold sheets");
  return mesh;
}

std::vector<Surfel> extract_surfels(const VoxelGrid& grid) {
  if (grid.empty_box()) return {};
  const Eigen::Vector3i lo = grid.lower(), n = grid.size();
  if ((n.array() * 2 + 4 >= (1 << kBits)).any())
    throw InputError("surface extraction: the box is too large (more than 1M voxels along an axis)");
  const SortedKeys sorted = sorted_surfel_keys(
      grid, [](std::size_t) {}, [](const char*) {});
  std::vector<Surfel> surfels(sorted.keys.size());
  for (std::size_t f = 0; f < surfels.size(); ++f) {
    surfels[f] = surfel_of(decode(sorted.keys[f]), lo);
  }
  return surfels;
}

Eigen::Vector3i surfel_corner_pointel(const Surfel& s, int c) {
  // corner_pointel is translation-invariant on the (even) Khalimsky coordinates: absolute ones
  // give absolute pointels.
  const Eigen::Vector3i kc = s.khalimsky();
  DecodedFace d;
  for (int a = 0; a < 3; ++a) d.kc[a] = kc[a];
  d.axis = s.axis;
  d.positive = s.positive();
  int q[3];
  corner_pointel(d, c, q);
  return {q[0], q[1], q[2]};
}

bool pointel_may_split(const VoxelGrid& grid, const Eigen::Vector3i& q) { return pointel_flagged(grid, q); }

}  // namespace corrlap

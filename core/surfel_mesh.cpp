#include "surfel_mesh.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <bit>
#include <cmath>
#include <sstream>

#include "error.hpp"

namespace corrlap {

Eigen::Vector3i Surfel::inner_voxel() const {
  return outward > 0 ? lower_voxel : Eigen::Vector3i(lower_voxel + Eigen::Vector3i::Unit(axis));
}
Eigen::Vector3i Surfel::outer_voxel() const {
  return outward > 0 ? Eigen::Vector3i(lower_voxel + Eigen::Vector3i::Unit(axis)) : lower_voxel;
}
Eigen::Vector3d Surfel::trivial_normal() const { return double(outward) * Eigen::Vector3d::Unit(axis); }
Eigen::Vector3i Surfel::khalimsky() const {
  return 2 * lower_voxel + Eigen::Vector3i::Unit(axis) + Eigen::Vector3i::Ones();
}
bool Surfel::positive() const {
  // spec §1.4: outward -e0 (k=0), +e1 (k=1), -e2 (k=2)
  return axis == 1 ? outward > 0 : outward < 0;
}

Eigen::MatrixX3d SurfelMesh::face_centroids() const {
  Eigen::MatrixX3d c(faces.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    c.row(f) = 0.25 * (positions.row(faces(f, 0)) + positions.row(faces(f, 1)) +
                       positions.row(faces(f, 2)) + positions.row(faces(f, 3)));
  return c;
}

Eigen::MatrixX3d SurfelMesh::face_normals_from_positions() const {
  Eigen::MatrixX3d n(faces.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) b += positions.row(faces(f, j)).transpose();
    b *= 0.25;
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector3d a = positions.row(faces(f, j)).transpose() - b;
      const Eigen::Vector3d c = positions.row(faces(f, (j + 1) % 4)).transpose() - b;
      s += a.cross(c);
    }
    const double len = s.norm();
    n.row(f) = len > 0 ? Eigen::RowVector3d((s / len).transpose()) : Eigen::RowVector3d::Zero();
  }
  return n;
}

double SurfelMesh::grid_step() const {
  if (h > 0) return h;
  if (faces.rows() == 0) return 0.0;
  double sum = 0.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int j = 0; j < 4; ++j) sum += (positions.row(faces(f, (j + 1) % 4)) - positions.row(faces(f, j))).norm();
  return sum / double(4 * faces.rows());
}

void SurfelMesh::validate(const char* what) const {
  const int nv = num_vertices();
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int j = 0; j < 4; ++j) {
      const int v = faces(f, j);
      if (v < 0 || v >= nv) {
        std::ostringstream os;
        os << what << ": face " << f << " refers to vertex " << v << " but there are " << nv << " vertices";
        throw InputError(os.str());
      }
      for (int k = 0; k < j; ++k)
        if (faces(f, k) == v) {
          std::ostringstream os;
          os << what << ": face " << f << " uses vertex " << v << " twice (degenerate quad)";
          throw InputError(os.str());
        }
    }
  for (Eigen::Index v = 0; v < positions.rows(); ++v)
    if (!positions.row(v).allFinite()) {
      std::ostringstream os;
      os << what << ": vertex " << v << " has a non-finite position";
      throw InputError(os.str());
    }
  if (!surfels.empty() && surfels.size() != std::size_t(faces.rows()))
    throw InputError(std::string(what) + ": surfel data does not match the number of faces");
}

namespace {

constexpr int kBits = 21;
constexpr std::uint64_t kMask = (std::uint64_t{1} << kBits) - 1;

// Surfel key (spec §1.4): positive flag, then Khalimsky coordinates relative to the box.
inline std::uint64_t surfel_key(bool positive, const Eigen::Vector3i& kc_rel) {
  return (std::uint64_t(positive) << 63) | (std::uint64_t(kc_rel.x()) << 42) |
         (std::uint64_t(kc_rel.y()) << 21) | std::uint64_t(kc_rel.z());
}

struct CornerRef {
  std::uint64_t pointel;  // relative pointel coordinates packed in 3 x 21 bits
  std::uint32_t occurrence;  // 4 * face + corner
  bool operator<(const CornerRef& o) const {
    return pointel < o.pointel || (pointel == o.pointel && occurrence < o.occurrence);
  }
};

// Calls emit(x, y, z, axis, lower_inside) for every transition between two voxels of the box.
template <class Emit>
void for_each_transition_in_slab(const VoxelGrid& g, int z, Emit&& emit) {
  const Eigen::Vector3i lo = g.lower(), up = g.upper(), n = g.size();
  const std::size_t W = g.words_per_row();
  for (int y = lo.y(); y <= up.y(); ++y) {
    const std::uint64_t* r = g.row(y, z);
    // axis 0: bit x vs bit x+1 in the same row
    for (std::size_t w = 0; w < W; ++w) {
      const std::uint64_t next = (w + 1 < W) ? r[w + 1] : 0;
      std::uint64_t t = r[w] ^ ((r[w] >> 1) | (next << 63));
      // valid local x: 0 .. n.x()-2
      const long base = long(w) * 64;
      const long last_valid = long(n.x()) - 2 - base;
      if (last_valid < 0) t = 0;
      else if (last_valid < 63) t &= (std::uint64_t{2} << last_valid) - 1;
      while (t) {
        const int b = std::countr_zero(t);
        t &= t - 1;
        const int lx = int(base) + b;
        emit(lo.x() + lx, y, z, 0, bool((r[w] >> b) & 1u));
      }
    }
    // axis 1: row y vs row y+1
    if (y < up.y()) {
      const std::uint64_t* s = g.row(y + 1, z);
      for (std::size_t w = 0; w < W; ++w) {
        std::uint64_t t = r[w] ^ s[w];
        while (t) {
          const int b = std::countr_zero(t);
          t &= t - 1;
          emit(lo.x() + int(w) * 64 + b, y, z, 1, bool((r[w] >> b) & 1u));
        }
      }
    }
    // axis 2: slab z vs slab z+1
    if (z < up.z()) {
      const std::uint64_t* s = g.row(y, z + 1);
      for (std::size_t w = 0; w < W; ++w) {
        std::uint64_t t = r[w] ^ s[w];
        while (t) {
          const int b = std::countr_zero(t);
          t &= t - 1;
          emit(lo.x() + int(w) * 64 + b, y, z, 2, bool((r[w] >> b) & 1u));
        }
      }
    }
  }
}

}  // namespace

SurfelMesh extract_surface(const VoxelGrid& grid) {
  if (grid.empty_box()) throw InputError("surface extraction: the voxel grid has no voxels");
  const Eigen::Vector3i lo = grid.lower(), n = grid.size();
  if ((n.array() * 2 + 4 >= (1 << kBits)).any())
    throw InputError("surface extraction: the box is too large (more than 1M voxels along an axis)");

  // 1. Surfel keys, slab by slab in parallel (spec §1.3).
  std::vector<std::vector<std::uint64_t>> per_slab(std::size_t(n.z()));
  tbb::parallel_for(0, n.z(), [&](int iz) {
    auto& out = per_slab[std::size_t(iz)];
    for_each_transition_in_slab(grid, lo.z() + iz, [&](int x, int y, int z, int axis, bool lower_inside) {
      Surfel s{Eigen::Vector3i(x, y, z), axis, lower_inside ? 1 : -1};
      out.push_back(surfel_key(s.positive(), s.khalimsky() - 2 * lo));
    });
  });
  std::size_t total = 0;
  for (const auto& v : per_slab) total += v.size();
  if (total == 0)
    throw InputError("surface extraction: the volume has no surfel (it is empty, full, or touches no voxel pair inside the box)");
  if (total > (std::size_t{1} << 30)) throw InputError("surface extraction: more than 2^30 surfels");
  std::vector<std::uint64_t> keys;
  keys.reserve(total);
  for (auto& v : per_slab) {
    keys.insert(keys.end(), v.begin(), v.end());
    std::vector<std::uint64_t>().swap(v);
  }
  // 2. Face order: ascending key = (positive, kc_x, kc_y, kc_z) (spec §1.4).
  tbb::parallel_sort(keys.begin(), keys.end());

  const std::size_t F = keys.size();
  SurfelMesh mesh;
  mesh.h = grid.h();
  mesh.surfels.resize(F);
  std::vector<CornerRef> corners(4 * F);
  tbb::parallel_for(std::size_t{0}, F, [&](std::size_t f) {
    const std::uint64_t key = keys[f];
    const bool positive = key >> 63;
    const Eigen::Vector3i kc(int((key >> 42) & kMask), int((key >> 21) & kMask), int(key & kMask));
    int axis = 0;
    while (kc[axis] % 2 != 0) ++axis;  // the even coordinate is the normal axis
    Surfel& s = mesh.surfels[f];
    s.axis = axis;
    s.outward = (axis == 1) == positive ? 1 : -1;
    // kc_rel = 2 (z - lo) + e_k + 1
    s.lower_voxel = (kc - Eigen::Vector3i::Unit(axis) - Eigen::Vector3i::Ones()) / 2 + lo;
    const int i = axis == 0 ? 1 : 0, j = axis == 2 ? 1 : 2;
    // Base order B = [(i-,j-),(i-,j+),(i+,j+),(i+,j-)], reversed for negative surfels.
    static constexpr int si[4] = {-1, -1, +1, +1}, sj[4] = {-1, +1, +1, -1};
    for (int c = 0; c < 4; ++c) {
      const int b = positive ? c : 3 - c;
      Eigen::Vector3i p = kc;  // pointel Khalimsky coordinates, all even
      p[i] += si[b];
      p[j] += sj[b];
      const Eigen::Vector3i q = p / 2;  // relative pointel index >= 0
      corners[4 * f + c] = {(std::uint64_t(q.x()) << 42) | (std::uint64_t(q.y()) << 21) | std::uint64_t(q.z()),
                            std::uint32_t(4 * f + c)};
    }
  });
  std::vector<std::uint64_t>().swap(keys);

  // 3. Vertices numbered by first appearance (spec §1.4): group equal pointels, order the groups
  //    by their first occurrence.
  tbb::parallel_sort(corners.begin(), corners.end());
  std::vector<std::uint32_t> group_first;  // first occurrence of each distinct pointel
  std::vector<std::uint32_t> group_of(corners.size());
  group_first.reserve(F + 2);
  for (std::size_t a = 0; a < corners.size(); ++a) {
    if (a == 0 || corners[a].pointel != corners[a - 1].pointel) group_first.push_back(corners[a].occurrence);
    group_of[a] = std::uint32_t(group_first.size() - 1);
  }
  const std::size_t V = group_first.size();
  // Rank groups by first occurrence: occurrences are unique, so scatter into a marker array.
  std::vector<std::int32_t> id_of_occurrence_rank(4 * F, -1);
  for (std::size_t g = 0; g < V; ++g) id_of_occurrence_rank[group_first[g]] = std::int32_t(g);
  std::vector<std::int32_t> vertex_of_group(V);
  {
    std::int32_t next = 0;
    for (std::size_t o = 0; o < 4 * F; ++o)
      if (id_of_occurrence_rank[o] >= 0) vertex_of_group[std::size_t(id_of_occurrence_rank[o])] = next++;
  }
  mesh.faces.resize(Eigen::Index(F), 4);
  mesh.positions.resize(Eigen::Index(V), 3);
  const double h = grid.h();
  tbb::parallel_for(std::size_t{0}, corners.size(), [&](std::size_t a) {
    const std::uint32_t o = corners[a].occurrence;
    const int v = vertex_of_group[group_of[a]];
    mesh.faces(Eigen::Index(o / 4), Eigen::Index(o % 4)) = v;
    if (o == group_first[group_of[a]]) {
      const std::uint64_t p = corners[a].pointel;
      // pointel relative index q -> Khalimsky 2(q + lo); corner in grid units = (kc - 1) / 2
      const Eigen::Vector3i kc = 2 * (Eigen::Vector3i(int((p >> 42) & kMask), int((p >> 21) & kMask), int(p & kMask)) + lo);
      for (int d = 0; d < 3; ++d) mesh.positions(v, d) = (double(kc[d] - 1) * 0.5) * h;
    }
  });
  return mesh;
}

}  // namespace corrlap

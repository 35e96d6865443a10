// The fast digitization / surface extraction / edge numbering (block culling, row evaluation,
// slab-parallel numbering) must give exactly the result of the plain definitions of docs/math.md §1.2-§1.4
// and §0. This file holds those plain definitions (voxel by voxel, std::map numbering) and compares.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <map>
#include <random>
#include <tuple>

using namespace corrlap;

namespace {

// docs/math.md §1.2, literally: voxel z is inside iff P(h z - c) <= 0, evaluated point by point.
VoxelGrid reference_digitize(const ImplicitShape& shape, const DigitizationParams& p) {
  Eigen::Vector3i lo, hi;
  digitization_box(p, lo, hi);
  VoxelGrid g(lo, hi, p.h);
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x)
        if (shape.inside(Eigen::Vector3d(x * p.h, y * p.h, z * p.h))) g.set(x, y, z, true);
  return g;
}

struct RefMesh {
  std::vector<std::array<double, 3>> positions;
  std::vector<std::array<int, 4>> faces;
  std::vector<std::tuple<int, int, int, int, int>> surfels;  // lower voxel, axis, outward
};

// docs/math.md §1.4, manifold sheets, literally: at every vertex, faces sharing a linel join one
// sheet; at a linel with four faces they pair by their inside voxel, or by their outside voxel when
// the two inside voxels are face-connected around the linel beyond both of its ends. The second and
// later sheets (ordered by smallest face) of each vertex, vertices in order, get new vertices.
void split_sheets(const VoxelGrid& g, RefMesh& m) {
  const int V = int(m.positions.size());
  std::vector<std::vector<int>> at(static_cast<std::size_t>(V));  // 4 face + corner, faces ascending
  for (std::size_t f = 0; f < m.faces.size(); ++f)
    for (int c = 0; c < 4; ++c) at[std::size_t(m.faces[f][std::size_t(c)])].push_back(int(4 * f) + c);
  auto grid_pointel = [&](int v) {
    return Eigen::Vector3i(int(std::lround(m.positions[std::size_t(v)][0] / g.h() + 0.5)),
                           int(std::lround(m.positions[std::size_t(v)][1] / g.h() + 0.5)),
                           int(std::lround(m.positions[std::size_t(v)][2] / g.h() + 0.5)));
  };
  auto in = [&](const Eigen::Vector3i& x) { return g.get(x.x(), x.y(), x.z()); };
  auto voxels_of = [&](int f) {
    const auto [x, y, z, k, o] = m.surfels[std::size_t(f)];
    const Eigen::Vector3i a(x, y, z), b = a + Eigen::Vector3i::Unit(k);
    return o > 0 ? std::pair{a, b} : std::pair{b, a};  // (inside, outside)
  };
  std::vector<std::pair<int, int>> moves;  // (4 face + corner, new vertex)
  int next = V;
  for (int v = 0; v < V; ++v) {
    const std::vector<int>& corners = at[std::size_t(v)];
    const int n = int(corners.size());
    std::vector<int> sheet(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) sheet[std::size_t(i)] = i;
    auto find = [&](int i) {
      while (sheet[std::size_t(i)] != i) i = sheet[std::size_t(i)];
      return i;
    };
    std::map<int, std::vector<int>> by_linel;  // neighbour vertex -> local faces
    for (int i = 0; i < n; ++i) {
      const auto& face = m.faces[std::size_t(corners[std::size_t(i)] / 4)];
      const int c = corners[std::size_t(i)] % 4;
      by_linel[face[std::size_t((c + 1) % 4)]].push_back(i);
      by_linel[face[std::size_t((c + 3) % 4)]].push_back(i);
    }
    for (const auto& [w, list] : by_linel) {
      bool outward_pairs = false;
      if (list.size() == 4) {
        const Eigen::Vector3i dir = grid_pointel(w) - grid_pointel(v);
        std::vector<Eigen::Vector3i> inside, outside;
        for (int i : list) {
          const auto [a, b] = voxels_of(corners[std::size_t(i)] / 4);
          if (std::find(inside.begin(), inside.end(), a) == inside.end()) inside.push_back(a);
          if (std::find(outside.begin(), outside.end(), b) == outside.end()) outside.push_back(b);
        }
        bool both = true;
        for (int sign : {-1, 1}) {
          const Eigen::Vector3i off = sign * dir;
          both = both && in(inside[0] + off) && in(inside[1] + off) && (in(outside[0] + off) || in(outside[1] + off));
        }
        outward_pairs = both;
      }
      for (std::size_t a = 0; a < list.size(); ++a)
        for (std::size_t b = a + 1; b < list.size(); ++b) {
          const auto [ia, oa] = voxels_of(corners[std::size_t(list[a])] / 4);
          const auto [ib, ob] = voxels_of(corners[std::size_t(list[b])] / 4);
          if (list.size() == 2 || (outward_pairs ? oa == ob : ia == ib))
            sheet[std::size_t(find(list[a]))] = find(list[b]);
        }
    }
    std::map<int, int> vertex_of_sheet;
    for (int i = 0; i < n; ++i) {
      const int root = find(i);
      if (!vertex_of_sheet.count(root)) {
        vertex_of_sheet[root] = vertex_of_sheet.empty() ? v : next++;
        if (vertex_of_sheet[root] != v) m.positions.push_back(m.positions[std::size_t(v)]);
      }
      if (vertex_of_sheet[root] != v) moves.push_back({corners[std::size_t(i)], vertex_of_sheet[root]});
    }
  }
  for (const auto& [corner, id] : moves) m.faces[std::size_t(corner / 4)][std::size_t(corner % 4)] = id;
}

// docs/math.md §1.3-§1.4, literally: surfels between voxel pairs of the box, sorted by
// (positive, kc_x, kc_y, kc_z); corners in base order B (reversed if negative); pointels numbered
// by first appearance through a std::map, then split into manifold sheets.
RefMesh reference_extract(const VoxelGrid& g) {
  using Key = std::tuple<int, int, int, int>;  // positive, kc
  std::map<Key, std::tuple<int, int, int, int, int>> sorted;
  const Eigen::Vector3i lo = g.lower(), up = g.upper();
  for (int z = lo.z(); z <= up.z(); ++z)
    for (int y = lo.y(); y <= up.y(); ++y)
      for (int x = lo.x(); x <= up.x(); ++x)
        for (int k = 0; k < 3; ++k) {
          Eigen::Vector3i a(x, y, z), b = a + Eigen::Vector3i::Unit(k);
          if (b[k] > up[k]) continue;
          const bool ia = g.get(a.x(), a.y(), a.z()), ib = g.get(b.x(), b.y(), b.z());
          if (ia == ib) continue;
          const int outward = ia ? 1 : -1;
          const bool positive = (k == 1) ? outward > 0 : outward < 0;
          const Eigen::Vector3i kc = 2 * a + Eigen::Vector3i::Unit(k) + Eigen::Vector3i::Ones();
          sorted[Key{positive ? 1 : 0, kc.x(), kc.y(), kc.z()}] = {x, y, z, k, outward};
        }
  RefMesh m;
  std::map<std::array<int, 3>, int> pointel_id;
  for (const auto& [key, s] : sorted) {
    const bool positive = std::get<0>(key) == 1;
    const Eigen::Vector3i kc(std::get<1>(key), std::get<2>(key), std::get<3>(key));
    const int k = std::get<3>(s);
    const int i = k == 0 ? 1 : 0, j = k == 2 ? 1 : 2;
    const int si[4] = {-1, -1, +1, +1}, sj[4] = {-1, +1, +1, -1};
    std::array<int, 4> face{};
    for (int c = 0; c < 4; ++c) {
      const int b = positive ? c : 3 - c;
      Eigen::Vector3i p = kc;
      p[i] += si[b];
      p[j] += sj[b];
      const std::array<int, 3> pk{p.x(), p.y(), p.z()};
      auto it = pointel_id.find(pk);
      if (it == pointel_id.end()) {
        it = pointel_id.emplace(pk, int(m.positions.size())).first;
        // Khalimsky pointel p (even) is the grid corner (p - 1) / 2 (half-integers).
        m.positions.push_back({(p.x() - 1) * 0.5 * g.h(), (p.y() - 1) * 0.5 * g.h(), (p.z() - 1) * 0.5 * g.h()});
      }
      face[std::size_t(c)] = it->second;
    }
    m.faces.push_back(face);
    m.surfels.push_back(s);
  }
  split_sheets(g, m);
  return m;
}

void check_same_grid(const VoxelGrid& fast, const VoxelGrid& ref) {
  REQUIRE(fast.lower() == ref.lower());
  REQUIRE(fast.upper() == ref.upper());
  std::int64_t differing = 0;
  for (int z = ref.lower().z(); z <= ref.upper().z(); ++z)
    for (int y = ref.lower().y(); y <= ref.upper().y(); ++y)
      for (int x = ref.lower().x(); x <= ref.upper().x(); ++x)
        if (fast.get(x, y, z) != ref.get(x, y, z)) ++differing;
  CHECK(differing == 0);
  CHECK(fast.count() == ref.count());  // also catches stray bits in the row padding
}

void check_same_mesh(const SurfelMesh& fast, const RefMesh& ref) {
  REQUIRE(std::size_t(fast.num_faces()) == ref.faces.size());
  REQUIRE(std::size_t(fast.num_vertices()) == ref.positions.size());
  REQUIRE(fast.surfels.size() == ref.surfels.size());
  int bad_faces = 0, bad_positions = 0, bad_surfels = 0;
  for (std::size_t f = 0; f < ref.faces.size(); ++f) {
    for (int c = 0; c < 4; ++c)
      if (fast.faces(Eigen::Index(f), c) != ref.faces[f][std::size_t(c)]) ++bad_faces;
    const auto& s = fast.surfels[f];
    const auto [x, y, z, k, o] = ref.surfels[f];
    if (s.lower_voxel != Eigen::Vector3i(x, y, z) || s.axis != k || s.outward != o) ++bad_surfels;
  }
  for (std::size_t v = 0; v < ref.positions.size(); ++v)
    for (int d = 0; d < 3; ++d)
      if (fast.positions(Eigen::Index(v), d) != ref.positions[v][std::size_t(d)]) ++bad_positions;  // bitwise
  CHECK(bad_faces == 0);
  CHECK(bad_surfels == 0);
  CHECK(bad_positions == 0);
}

// docs/math.md §0: edges (min, max) numbered by lexicographic rank; sign +1 iff v_i < v_{i+1}.
void check_edges(const SurfelMesh& m) {
  std::map<std::pair<int, int>, int> rank, count;
  for (int f = 0; f < m.num_faces(); ++f)
    for (int i = 0; i < 4; ++i) {
      const int a = m.faces(f, i), b = m.faces(f, (i + 1) % 4);
      rank[{std::min(a, b), std::max(a, b)}] = 0;
      count[{std::min(a, b), std::max(a, b)}] += 1;
    }
  int r = 0;
  for (auto& [e, id] : rank) id = r++;
  const EdgeTopology t = build_edges(m);
  REQUIRE(std::size_t(t.num_edges()) == rank.size());
  int bad = 0;
  for (const auto& [e, id] : rank) {
    if (t.edges(id, 0) != e.first || t.edges(id, 1) != e.second) ++bad;
    if (t.faces_per_edge[std::size_t(id)] != count[e]) ++bad;
  }
  for (int f = 0; f < m.num_faces(); ++f)
    for (int i = 0; i < 4; ++i) {
      const int a = m.faces(f, i), b = m.faces(f, (i + 1) % 4);
      if (t.face_edges(f, i) != rank[{std::min(a, b), std::max(a, b)}]) ++bad;
      if (t.face_edge_signs(f, i) != (a < b ? 1 : -1)) ++bad;
    }
  CHECK(bad == 0);
}

void check_shape(const std::string& name, const Eigen::Vector3d& centre, double h, double lo, double hi) {
  CAPTURE(name);
  CAPTURE(h);
  DigitizationParams p;
  p.h = h;
  p.min_aabb = lo;
  p.max_aabb = hi;
  const ImplicitShape shape = make_implicit_shape(name, centre);
  const VoxelGrid ref_grid = reference_digitize(shape, p);
  const VoxelGrid fast_grid = digitize(shape, p);
  check_same_grid(fast_grid, ref_grid);
  const SurfelMesh fast = extract_surface(fast_grid);
  check_same_mesh(fast, reference_extract(ref_grid));
  check_edges(fast);
}

}  // namespace

TEST_CASE("fast digitization and extraction equal the plain definitions on an off-centre sphere") {
  check_shape("sphere1", Eigen::Vector3d(0.137, -0.291, 0.403), 0.05, -1.5, 1.5);
  // h = 0.5 puts sample points exactly on the sphere, where rounding decides inside/outside.
  check_shape("sphere1", Eigen::Vector3d::Zero(), 0.5, -1.5, 1.5);
  check_shape("sphere1", Eigen::Vector3d::Zero(), 0.0625, -1.5, 1.5);
}

TEST_CASE("fast digitization and extraction equal the plain definitions on torus and goursat") {
  check_shape("torus", Eigen::Vector3d(0.31, 0.17, -0.05), 0.4, -10, 10);
  check_shape("goursat", Eigen::Vector3d::Zero(), 0.3, -10, 10);
  check_shape("goursat-hole", Eigen::Vector3d(0.01, 0.02, 0.03), 0.25, -5, 5);
}

TEST_CASE("fast digitization and extraction equal the plain definitions on a saddle crossing the box") {
  check_shape("0.1*y*y -0.1*x*x - 2.0*z", Eigen::Vector3d::Zero(), 0.5, -10, 10);
  check_shape("0.1*y*y -0.1*x*x - 2.0*z", Eigen::Vector3d(0.2, -0.1, 0.3), 0.3, -7, 9);
}

TEST_CASE("fast extraction equals the plain definition on random voxel sets (pinched voxels, box faces)") {
  // Random bits give every local configuration, including voxels touching only along an edge or
  // a vertex and surfels on the box boundary. Box widths around 64 exercise the row padding.
  std::mt19937 rng(12345);
  for (const Eigen::Vector3i& size : {Eigen::Vector3i(5, 7, 3), Eigen::Vector3i(63, 4, 5), Eigen::Vector3i(64, 3, 6),
                                      Eigen::Vector3i(65, 6, 4), Eigen::Vector3i(130, 9, 8)}) {
    for (double density : {0.1, 0.5, 0.9}) {
      CAPTURE(size.transpose());
      CAPTURE(density);
      const Eigen::Vector3i lo(-3, 2, -7);
      VoxelGrid g(lo, lo + size - Eigen::Vector3i::Ones(), 0.25);
      std::bernoulli_distribution bit(density);
      for (int z = g.lower().z(); z <= g.upper().z(); ++z)
        for (int y = g.lower().y(); y <= g.upper().y(); ++y)
          for (int x = g.lower().x(); x <= g.upper().x(); ++x)
            if (bit(rng)) g.set(x, y, z, true);
      const SurfelMesh fast = extract_surface(g);
      check_same_mesh(fast, reference_extract(g));
      check_edges(fast);
    }
  }
}

TEST_CASE("digitization, extraction and edges do not depend on the thread count") {
  // The parallel work is split into fixed pieces (64^3 tiles, 64 row chunks, pointel slabs), so
  // one thread and all threads must give identical meshes.
  DigitizationParams p;
  p.h = 0.25;
  const ImplicitShape shape = make_implicit_shape("goursat", Eigen::Vector3d(0.05, -0.02, 0.07));
  const int before = thread_count();
  set_thread_count(1);
  const SurfelMesh one = extract_surface(digitize(shape, p));
  const EdgeTopology e1 = build_edges(one);
  set_thread_count(0);
  const SurfelMesh all = extract_surface(digitize(shape, p));
  const EdgeTopology ea = build_edges(all);
  set_thread_count(before);
  REQUIRE(one.num_faces() == all.num_faces());
  REQUIRE(one.num_vertices() == all.num_vertices());
  CHECK(one.faces == all.faces);
  CHECK(one.positions == all.positions);
  CHECK(e1.edges == ea.edges);
  CHECK(e1.face_edges == ea.face_edges);
  CHECK(e1.faces_per_edge == ea.faces_per_edge);
}

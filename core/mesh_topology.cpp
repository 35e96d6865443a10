#include "mesh_topology.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>
#include <sstream>

#include "error.hpp"

namespace corrlap {

EdgeTopology build_edges(const SurfelMesh& mesh) {
  // docs/math.md §0: undirected edges (min, max) numbered by lexicographic rank. Instead of sorting the 4F
  // half-edges, bucket them by their smaller vertex (counting sort, stable in half-edge order),
  // sort each short bucket by the larger vertex, and number edges by a prefix sum over buckets.
  const std::size_t F = std::size_t(mesh.num_faces());
  if (4 * F >= (std::size_t{1} << 32)) throw InputError("edges: too many faces");
  int max_id = mesh.num_vertices() - 1;
  for (std::size_t f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i) {
      const int v = mesh.faces(Eigen::Index(f), i);
      if (v < 0) {
        std::ostringstream os;
        os << "edges: face " << f << " has a negative vertex id " << v;
        throw InputError(os.str());
      }
      max_id = std::max(max_id, v);
    }
  const std::size_t V = std::size_t(max_id) + 1;
  const int* fv = mesh.faces.data();  // row-major F x 4
  std::vector<std::uint32_t> start(V + 1, 0);
  for (std::size_t k = 0; k < 4 * F; ++k) {
    const int a = fv[k], b = fv[(k & ~std::size_t{3}) + ((k + 1) & 3)];
    ++start[std::size_t(std::min(a, b)) + 1];
  }
  for (std::size_t v = 0; v < V; ++v) start[v + 1] += start[v];
  struct Slot {
    std::uint32_t other;      // the larger vertex
    std::uint32_t half_edge;  // 4 f + i
  };
  std::vector<Slot> slots(4 * F);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < 4 * F; ++k) {
      const int a = fv[k], b = fv[(k & ~std::size_t{3}) + ((k + 1) & 3)];
      slots[fill[std::size_t(std::min(a, b))]++] = {std::uint32_t(std::max(a, b)), std::uint32_t(k)};
    }
  }
  // Per bucket: stable insertion sort by the larger vertex (buckets hold a few entries), count
  // distinct edges.
  std::vector<std::uint32_t> edge_start(V + 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, V, 2048), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      Slot* b = slots.data() + start[v];
      const std::size_t m = start[v + 1] - start[v];
      for (std::size_t x = 1; x < m; ++x) {
        const Slot s = b[x];
        std::size_t y = x;
        while (y > 0 && b[y - 1].other > s.other) {
          b[y] = b[y - 1];
          --y;
        }
        b[y] = s;
      }
      std::uint32_t distinct = 0;
      for (std::size_t x = 0; x < m; ++x)
        if (x == 0 || b[x].other != b[x - 1].other) ++distinct;
      edge_start[v + 1] = distinct;
    }
  });
  for (std::size_t v = 0; v < V; ++v) edge_start[v + 1] += edge_start[v];
  const std::size_t E = edge_start[V];
  EdgeTopology t;
  t.face_edges.resize(Eigen::Index(F), 4);
  t.face_edge_signs.resize(Eigen::Index(F), 4);
  t.edges.resize(Eigen::Index(E), 2);
  t.faces_per_edge.assign(E, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, V, 2048), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      const Slot* b = slots.data() + start[v];
      const std::size_t m = start[v + 1] - start[v];
      std::size_t e = std::size_t(edge_start[v]) - 1;
      for (std::size_t x = 0; x < m; ++x) {
        if (x == 0 || b[x].other != b[x - 1].other) {
          ++e;
          t.edges(Eigen::Index(e), 0) = int(v);
          t.edges(Eigen::Index(e), 1) = int(b[x].other);
        }
        t.faces_per_edge[e] += 1;
        const std::uint32_t k = b[x].half_edge;
        t.face_edges(Eigen::Index(k / 4), Eigen::Index(k % 4)) = int(e);
      }
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f != r.end(); ++f)
      for (int i = 0; i < 4; ++i)
        t.face_edge_signs(Eigen::Index(f), i) =
            fv[4 * f + std::size_t(i)] < fv[4 * f + std::size_t((i + 1) % 4)] ? std::int8_t(1) : std::int8_t(-1);
  });
  return t;
}

namespace {
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(std::size_t(n)) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) {
    while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
    return a;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
  }
};
}  // namespace

std::vector<int> face_components(const SurfelMesh& mesh, int& num_components) {
  const int F = mesh.num_faces(), V = mesh.num_vertices();
  UnionFind uf(F + V);
  for (int f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i) uf.unite(f, F + mesh.faces(f, i));
  std::vector<int> label(std::size_t(F + V), -1);
  std::vector<int> comp(static_cast<std::size_t>(F), 0);
  num_components = 0;
  for (int f = 0; f < F; ++f) {
    const int r = uf.find(f);
    if (label[std::size_t(r)] < 0) label[std::size_t(r)] = num_components++;
    comp[std::size_t(f)] = label[std::size_t(r)];
  }
  return comp;
}

int MeshInfo::genus() const {
  if (!closed() || !manifold() || components == 0) return -1;
  const int twice_g = 2 * components - euler;
  return twice_g % 2 == 0 ? twice_g / 2 : -1;
}

MeshInfo compute_mesh_info(const SurfelMesh& mesh, const EdgeTopology& t) {
  MeshInfo info;
  info.vertices = mesh.num_vertices();
  info.faces = mesh.num_faces();
  info.edges = t.num_edges();
  info.euler = info.vertices - info.edges + info.faces;
  face_components(mesh, info.components);
  for (int c : t.faces_per_edge) {
    if (c == 1) ++info.boundary_edges;
    if (c > 2) ++info.nonmanifold_edges;
  }
  // Non-manifold vertices: the faces around a vertex, joined when they share an edge at that
  // vertex, must form a single fan. Two voxels touching only at a vertex give two fans.
  const int V = info.vertices, F = info.faces;
  std::vector<int> start(std::size_t(V) + 1, 0);
  for (int f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i) ++start[std::size_t(mesh.faces(f, i)) + 1];
  for (int v = 0; v < V; ++v) start[std::size_t(v) + 1] += start[std::size_t(v)];
  // static_cast, not std::size_t(...): clang parses "incident(std::size_t(start[n]))" as a function
  // declaration (most vexing parse); braces would pick the initializer-list constructor.
  std::vector<int> incident(static_cast<std::size_t>(start[std::size_t(V)])), fill(start.begin(), start.end() - 1);
  for (int f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i) incident[std::size_t(fill[std::size_t(mesh.faces(f, i))]++)] = 4 * f + i;
  for (int v = 0; v < V; ++v) {
    const int b = start[std::size_t(v)], e = start[std::size_t(v) + 1], n = e - b;
    if (n == 0) {
      ++info.isolated_vertices;
      continue;
    }
    UnionFind uf(n);
    for (int a = 0; a < n; ++a)
      for (int c = a + 1; c < n; ++c) {
        const int fa = incident[std::size_t(b + a)] / 4, ia = incident[std::size_t(b + a)] % 4;
        const int fc = incident[std::size_t(b + c)] / 4, ic = incident[std::size_t(b + c)] % 4;
        // neighbours of v in each face
        const int pa = mesh.faces(fa, (ia + 3) % 4), na = mesh.faces(fa, (ia + 1) % 4);
        const int pc = mesh.faces(fc, (ic + 3) % 4), nc = mesh.faces(fc, (ic + 1) % 4);
        if (pa == pc || pa == nc || na == pc || na == nc) uf.unite(a, c);
      }
    int fans = 0;
    for (int a = 0; a < n; ++a)
      if (uf.find(a) == a) ++fans;
    if (fans > 1) ++info.nonmanifold_vertices;
  }
  for (int f = 0; f < F; ++f) {
    const Eigen::Vector3d x0 = mesh.positions.row(mesh.faces(f, 0)), x1 = mesh.positions.row(mesh.faces(f, 1));
    const Eigen::Vector3d x2 = mesh.positions.row(mesh.faces(f, 2)), x3 = mesh.positions.row(mesh.faces(f, 3));
    info.area += 0.5 * ((x2 - x0).cross(x3 - x1)).norm();
  }
  if (V > 0) {
    info.bbox_min = mesh.positions.colwise().minCoeff().transpose();
    info.bbox_max = mesh.positions.colwise().maxCoeff().transpose();
  }
  return info;
}

}  // namespace corrlap

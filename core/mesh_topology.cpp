#include "mesh_topology.hpp"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>

namespace corrlap {

EdgeTopology build_edges(const SurfelMesh& mesh) {
  const std::size_t F = std::size_t(mesh.num_faces());
  // (min, max, half-edge id) sorted: edge ids are the ranks of distinct (min, max) pairs.
  struct HalfEdge {
    std::uint64_t key;
    std::uint32_t id;
    bool operator<(const HalfEdge& o) const { return key < o.key || (key == o.key && id < o.id); }
  };
  std::vector<HalfEdge> he(4 * F);
  for (std::size_t f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t a = std::uint32_t(mesh.faces(Eigen::Index(f), i));
      const std::uint32_t b = std::uint32_t(mesh.faces(Eigen::Index(f), (i + 1) % 4));
      he[4 * f + i] = {(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b), std::uint32_t(4 * f + i)};
    }
  tbb::parallel_sort(he.begin(), he.end());
  EdgeTopology t;
  t.face_edges.resize(Eigen::Index(F), 4);
  t.face_edge_signs.resize(Eigen::Index(F), 4);
  std::vector<std::uint64_t> distinct;
  distinct.reserve(2 * F + 8);
  for (std::size_t k = 0; k < he.size(); ++k) {
    if (k == 0 || he[k].key != he[k - 1].key) {
      distinct.push_back(he[k].key);
      t.faces_per_edge.push_back(0);
    }
    const int e = int(distinct.size() - 1);
    t.faces_per_edge[std::size_t(e)] += 1;
    const std::uint32_t f = he[k].id / 4, i = he[k].id % 4;
    t.face_edges(f, i) = e;
    t.face_edge_signs(f, i) =
        mesh.faces(f, i) < mesh.faces(f, (i + 1) % 4) ? std::int8_t(1) : std::int8_t(-1);
  }
  t.edges.resize(Eigen::Index(distinct.size()), 2);
  for (std::size_t e = 0; e < distinct.size(); ++e) {
    t.edges(Eigen::Index(e), 0) = int(distinct[e] >> 32);
    t.edges(Eigen::Index(e), 1) = int(distinct[e] & 0xffffffffu);
  }
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
  std::vector<int> incident(std::size_t(start[std::size_t(V)])), fill(start.begin(), start.end() - 1);
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

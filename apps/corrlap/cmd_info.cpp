// corrlap info: counts and topology of a mesh file: a quad (surfel) mesh, or any polygon mesh
// (the triangle meshes that reconstruct and study cotan read).
#include <algorithm>
#include <cmath>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <vector>

#include "command.hpp"
#include "library_errors.hpp"

namespace corrlap::cli {
namespace {

struct InfoArgs {
  std::string file;
  bool json = false;
};

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[std::size_t(x)] != x) x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
    return x;
  }
  void join(int a, int b) { parent[std::size_t(find(a))] = find(b); }
};

// The counts of compute_mesh_info for faces of any size: edges by their number of faces,
// components of faces joined by shared vertices, and a vertex non-manifold when its incident face
// corners form more than one fan (corners joined across the edges they share). Area: each face's
// vector area (exact for planar faces).
MeshInfo polygon_mesh_info(const PolygonMesh& mesh) {
  MeshInfo info;
  const int nv = int(mesh.positions.rows());
  info.vertices = nv;
  info.faces = int(mesh.faces.size());
  std::vector<int> corner_start(mesh.faces.size() + 1, 0);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) corner_start[f + 1] = corner_start[f] + int(mesh.faces[f].size());
  // Each undirected edge: the corners (of its two end points) of every face along it.
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> edges;
  UnionFind vertices(static_cast<std::size_t>(nv)), corners(static_cast<std::size_t>(corner_start.back()));
  std::vector<std::vector<int>> vertex_corners(static_cast<std::size_t>(nv));
  std::vector<char> used(static_cast<std::size_t>(nv), 0);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto face = mesh.faces[f];
    const int n = int(face.size());
    Eigen::Vector3d vector_area = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) {
      const int a = face[std::size_t(i)], b = face[std::size_t((i + 1) % n)];
      const int ca = corner_start[f] + i, cb = corner_start[f] + (i + 1) % n;
      vertex_corners[std::size_t(a)].push_back(ca);
      used[std::size_t(a)] = 1;
      vertices.join(a, b);
      edges[std::minmax(a, b)].push_back(a < b ? std::pair{ca, cb} : std::pair{cb, ca});
      vector_area += mesh.positions.row(a).transpose().cross(mesh.positions.row(b).transpose());
    }
    info.area += 0.5 * vector_area.norm();
  }
  info.edges = int(edges.size());
  for (const auto& [edge, along] : edges) {
    if (along.size() == 1) ++info.boundary_edges;
    if (along.size() > 2) ++info.nonmanifold_edges;
    if (along.size() != 2) continue;  // a fan crosses manifold edges only
    corners.join(along[0].first, along[1].first);
    corners.join(along[0].second, along[1].second);
  }
  std::vector<char> is_root(static_cast<std::size_t>(nv), 0);
  for (int v = 0; v < nv; ++v) {
    if (!used[std::size_t(v)]) {
      ++info.isolated_vertices;
      continue;
    }
    is_root[std::size_t(vertices.find(v))] = 1;
    std::vector<int> fans;
    for (int c : vertex_corners[std::size_t(v)]) fans.push_back(corners.find(c));
    std::sort(fans.begin(), fans.end());
    if (std::unique(fans.begin(), fans.end()) - fans.begin() > 1) ++info.nonmanifold_vertices;
  }
  info.components = int(std::count(is_root.begin(), is_root.end(), 1));
  info.euler = info.vertices - info.edges + info.faces;
  if (nv > 0) {
    info.bbox_min = mesh.positions.colwise().minCoeff().transpose();
    info.bbox_max = mesh.positions.colwise().maxCoeff().transpose();
  }
  return info;
}

void run(const InfoArgs& a) {
  // A quad mesh (or one without faces, refused with the quad loader's message) as the surface
  // loader reads it, with the digital area; any other mesh as polygons.
  const PolygonMesh polygons = in_cli_terms([&] { return read_mesh(a.file); });
  const bool quads = polygons.faces.empty() || polygons.all_quads();
  const MeshInfo info =
      quads ? compute_mesh_info(in_cli_terms([&] { return to_surfel_mesh(polygons, "mesh file '" + a.file + "'"); }))
            : polygon_mesh_info(polygons);
  if (a.json) {
    nlohmann::json j;
    j["file"] = a.file;
    j["vertices"] = info.vertices;
    j["faces"] = info.faces;
    j["edges"] = info.edges;
    j["euler"] = info.euler;
    j["components"] = info.components;
    j["genus"] = info.genus();
    j["closed"] = info.closed();
    j["manifold"] = info.manifold();
    j["boundary_edges"] = info.boundary_edges;
    j["nonmanifold_edges"] = info.nonmanifold_edges;
    j["nonmanifold_vertices"] = info.nonmanifold_vertices;
    j["isolated_vertices"] = info.isolated_vertices;
    j["area"] = info.area;
    j["faces_kind"] = quads ? "quads" : polygons.all_triangles() ? "triangles" : "polygons";
    j["bbox_min"] = {info.bbox_min.x(), info.bbox_min.y(), info.bbox_min.z()};
    j["bbox_max"] = {info.bbox_max.x(), info.bbox_max.y(), info.bbox_max.z()};
    std::cout << j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    return;
  }
  std::cout << "file                  " << a.file << "\n"
            << "vertices              " << info.vertices << "\n"
            << "edges                 " << info.edges << "\n"
            << "faces                 " << info.faces << "\n"
            << "euler characteristic  " << info.euler << "\n"
            << "components            " << info.components << "\n"
            << "genus                 "
            << (info.genus() >= 0 ? std::to_string(info.genus()) : "n/a (open or non-manifold)") << "\n"
            << "boundary edges        " << info.boundary_edges << "\n"
            << "non-manifold edges    " << info.nonmanifold_edges << "\n"
            << "non-manifold vertices " << info.nonmanifold_vertices << "\n"
            << (quads ? "area (digital)        " : "area                  ") << info.area << "\n"
            << "bounding box          [" << info.bbox_min.transpose() << "] .. [" << info.bbox_max.transpose() << "]\n";
}

RegisterCommand reg(20, "info", [](CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  auto* cmd = app.add_subcommand(
      "info", "counts, topology, area and bounding box of a mesh: quads (surfels), triangles or polygons");
  cmd->add_option("file", args->file, "mesh file (.obj, .ply, .off)")->required();
  cmd->add_flag("--json", args->json, "print a JSON object");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

// corrlap info: counts and topology of a mesh file.
#include <cmath>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <iostream>
#include <nlohmann/json.hpp>

#include "command.hpp"
#include "library_errors.hpp"

namespace corrlap::cli {
namespace {

struct InfoArgs {
  std::string file;
  bool json = false;
};

void run(const InfoArgs& a) {
  QuadMeshInput input;
  input.path = a.file;
  const SurfelMesh mesh = in_cli_terms([&] { return load_surface(input).mesh; });
  const MeshInfo info = compute_mesh_info(mesh);
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
            << "area (digital)        " << info.area << "\n"
            << "bounding box          [" << info.bbox_min.transpose() << "] .. [" << info.bbox_max.transpose() << "]\n";
}

RegisterCommand reg(20, "info", [](CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  auto* cmd = app.add_subcommand("info", "counts, topology, area and bounding box of a quad mesh");
  cmd->add_option("file", args->file, "mesh file (.obj)")->required();
  cmd->add_flag("--json", args->json, "print a JSON object");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

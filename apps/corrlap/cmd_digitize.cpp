// corrlap digitize: implicit shape or volume -> digital surface mesh (+ optional normals).
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <iostream>

#include "command.hpp"
#include "library_errors.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {
namespace {

struct DigitizeArgs {
  SurfaceSource source;
  std::string out, face_normals_out, vertex_normals_out, normals = "auto";
  std::string output_units = "world";
  std::string volume_out;  // the voxels as a volume file (255 inside)
};

void run(const DigitizeArgs& a) {
  const LoadedSurface loaded = a.source.load();
  if (!a.volume_out.empty()) {
    VolumeWriteOptions options;
    const std::string ext = file_extension(a.volume_out);
    options.compressed = (ext == "vol" || ext == "longvol") && nrrd_gzip_supported();  // Version 3, as DGtal
    write_volume(a.volume_out, voxels_to_volume(*loaded.grid), options);
    std::cerr << "wrote " << a.volume_out << " (" << loaded.grid->size().x() << "x" << loaded.grid->size().y() << "x"
              << loaded.grid->size().z() << " voxels, 255 inside" << (options.compressed ? ", Version 3" : "") << ")\n";
  }
  const SurfelMesh& mesh = loaded.mesh;
  const bool ply = file_extension(a.out) == "ply";
  const bool want_normals = !a.face_normals_out.empty() || !a.vertex_normals_out.empty() || ply;
  MeshAttributes attributes;
  if (want_normals) {
    // auto: true normals of a shape, else the surfel normals (no estimation while digitizing).
    NormalRequest request;
    request.source = a.normals == "auto" ? (loaded.shape ? NormalSource::True : NormalSource::Trivial)
                                         : parse_normal_source(a.normals);
    // docs/math.md §1.5: vertex normals = normalized sum of incident face normals (the reference's choice)
    const NormalFields n =
        in_cli_terms([&] { return resolve_normals(loaded, NormalKind::Vertex, request, "digitize"); });
    if (!a.face_normals_out.empty()) write_normals(a.face_normals_out, n.face);
    if (!a.vertex_normals_out.empty()) write_normals(a.vertex_normals_out, n.vertex);
    attributes.face_normals = n.face;  // PLY output carries them too
    attributes.vertex_normals = n.vertex;
  }
  if (!a.out.empty()) write_mesh(a.out, OutputUnits::parse(a.output_units, loaded).mesh(mesh), attributes);
  std::cerr << "digitized " << loaded.description << ": " << mesh.num_vertices() << " vertices, " << mesh.num_faces()
            << " faces" << (a.out.empty() ? "" : " -> " + a.out) << "\n";
}

RegisterCommand reg(10, "digitize", [](CLI::App& app) {
  auto args = std::make_shared<DigitizeArgs>();
  auto* cmd = app.add_subcommand("digitize",
                                 "digitize an implicit shape, a volume or a closed triangle mesh into a surfel mesh");
  args->source.add_options(*cmd, /*with_mesh=*/false);
  cmd->add_option("--out", args->out, "output mesh (.obj, or .ply with face and vertex normals)");
  cmd->add_option(
      "--volume-out", args->volume_out,
      "also write the voxels as a volume (.vol, .longvol: Version 3 with zlib, .nrrd, .raw; 255 inside, 0 outside)");
  cmd->add_option("--output-units", args->output_units,
                  "world: positions h z (volumes centred, docs/io.md); voxels: the input's voxel units (a volume "
                  "file's voxel indices; pointels at half-integers)")
      ->check(CLI::IsMember({"world", "voxels"}))
      ->capture_default_str();
  cmd->add_option("--face-normals", args->face_normals_out, "write one normal per face (text, nx ny nz)");
  cmd->add_option("--vertex-normals", args->vertex_normals_out,
                  "write one normal per vertex: normalized sum of incident face normals");
  cmd->add_option("--normals", args->normals, "kind of normals written: true (implicit shapes), trivial, auto")
      ->check(CLI::IsMember({"auto", "true", "trivial"}));
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

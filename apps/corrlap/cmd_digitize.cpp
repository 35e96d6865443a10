// corrlap digitize: implicit shape or volume -> digital surface mesh (+ optional normals).
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <iostream>
#include <optional>

#include "command.hpp"
#include "library_errors.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {
namespace {

struct DigitizeArgs {
  SurfaceSource source;
  std::string out, face_normals_out, vertex_normals_out, normals = "auto";
  OutputOptions output;
  std::string volume_out;  // the voxels as a volume file (255 inside)
};

void run(const DigitizeArgs& a) {
  // Every output checked before the computation, and all of them put in place together at the end:
  // a failure leaves none of them.
  if (const std::string ext = file_extension(a.out); !a.out.empty() && ext != "obj" && ext != "ply")
    throw IoError("mesh file '" + a.out + "': unsupported extension '" + ext + "' for writing (supported: .obj, .ply)",
                  "out");
  std::optional<StagedFile> out, volume_out, face_normals_out, vertex_normals_out;
  if (!a.out.empty()) out.emplace(a.out, "out");
  if (!a.volume_out.empty()) volume_out.emplace(a.volume_out, "volume_out");
  if (!a.face_normals_out.empty()) face_normals_out.emplace(a.face_normals_out, "face_normals");
  if (!a.vertex_normals_out.empty()) vertex_normals_out.emplace(a.vertex_normals_out, "vertex_normals");
  const LoadedSurface loaded = a.source.load();
  std::string volume_note;
  if (volume_out) {
    VolumeWriteOptions options;
    const std::string ext = file_extension(a.volume_out);
    options.compressed = (ext == "vol" || ext == "longvol") && nrrd_gzip_supported();  // Version 3, as DGtal
    write_volume(volume_out->path(), voxels_to_volume(*loaded.grid), options);
    volume_note = "wrote " + a.volume_out + " (" + std::to_string(loaded.grid->size().x()) + "x" +
                  std::to_string(loaded.grid->size().y()) + "x" + std::to_string(loaded.grid->size().z()) +
                  " voxels, 255 inside" + (options.compressed ? ", Version 3" : "") + ")\n";
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
    if (face_normals_out) write_normals(face_normals_out->path(), n.face);
    if (vertex_normals_out) write_normals(vertex_normals_out->path(), n.vertex);
    attributes.face_normals = n.face;  // PLY output carries them too
    attributes.vertex_normals = n.vertex;
  }
  if (out) {
    const OutputUnits units = a.output.parse(loaded);
    if (attributes.face_normals.rows() > 0) attributes.face_normals = units.normals(attributes.face_normals);
    if (attributes.vertex_normals.rows() > 0) attributes.vertex_normals = units.normals(attributes.vertex_normals);
    attributes.comments = units.comments();
    write_mesh(out->path(), units.mesh(mesh), attributes);
  }
  for (std::optional<StagedFile>* f : {&volume_out, &face_normals_out, &vertex_normals_out, &out})
    if (*f) (*f)->commit();
  std::cerr << volume_note;
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
  args->output.add_options(*cmd);
  cmd->add_option("--face-normals", args->face_normals_out, "write one normal per face (text, nx ny nz)");
  cmd->add_option("--vertex-normals", args->vertex_normals_out,
                  "write one normal per vertex: normalized sum of incident face normals");
  cmd->add_option("--normals", args->normals, "kind of normals written: true (implicit shapes), trivial, auto")
      ->check(CLI::IsMember({"auto", "true", "trivial"}));
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

// corrlap digitize: implicit shape or volume -> digital surface mesh (+ optional normals).
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <iostream>
#include <optional>

#include "command.hpp"
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
  // Voxel units need the volume's centring shift, which load() records.
  std::optional<LoadedSurface> loaded;
  if (a.output_units != "world" || !a.volume_out.empty()) loaded = a.source.load();
  if (!a.volume_out.empty()) {
    if (!loaded->grid) throw InputError("--volume-out needs voxels (--shape, --polynomial, --volume or --mesh-file)");
    VolumeWriteOptions options;
    const std::string ext = file_extension(a.volume_out);
    options.compressed = (ext == "vol" || ext == "longvol") && nrrd_gzip_supported();  // Version 3, as DGtal
    write_volume(a.volume_out, voxels_to_volume(*loaded->grid), options);
    std::cerr << "wrote " << a.volume_out << " (" << loaded->grid->size().x() << "x" << loaded->grid->size().y() << "x"
              << loaded->grid->size().z() << " voxels, 255 inside" << (options.compressed ? ", Version 3" : "")
              << ")\n";
  }
  SurfelMesh mesh = loaded ? loaded->mesh : a.source.surface();
  const bool ply = file_extension(a.out) == "ply";
  const bool want_normals = !a.face_normals_out.empty() || !a.vertex_normals_out.empty() || ply;
  MeshAttributes attributes;
  if (want_normals) {
    std::string kind = a.normals;
    auto shape = a.source.implicit_shape();
    if (kind == "auto") kind = shape ? "true" : "trivial";
    if (kind == "true" && !shape) throw InputError("--normals true needs an implicit shape (--shape or --polynomial)");
    const Eigen::MatrixX3d fn = kind == "true" ? true_face_normals(*shape, mesh) : mesh.face_normals_from_positions();
    // docs/math.md §1.5: vertex normals = normalized sum of incident face normals (the reference's choice)
    const Eigen::MatrixX3d vn = vertex_normals_from_face_normals(fn, mesh.faces, mesh.num_vertices());
    if (!a.face_normals_out.empty()) write_normals(a.face_normals_out, fn);
    if (!a.vertex_normals_out.empty()) write_normals(a.vertex_normals_out, vn);
    attributes.face_normals = fn;  // PLY output carries them too
    attributes.vertex_normals = vn;
  }
  if (!a.out.empty())
    write_mesh(a.out, loaded ? OutputUnits::parse(a.output_units, *loaded).mesh(mesh) : mesh, attributes);
  std::cerr << "digitized " << a.source.describe() << ": " << mesh.num_vertices() << " vertices, " << mesh.num_faces()
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

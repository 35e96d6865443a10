#include "surface_source.hpp"

#include <corrlap/core/error.hpp>
#include <iostream>

#include "library_errors.hpp"
#include "validators.hpp"

namespace corrlap::cli {

void SurfaceSource::add_options(CLI::App& cmd, bool with_mesh) {
  allow_mesh = with_mesh;
  auto* g = cmd.add_option_group("surface", "where the digital surface comes from (one of)");
  auto* s = g->add_option("--shape", shape, "named implicit shape (sphere1, torus, goursat, ...)");
  auto* p = g->add_option("--polynomial", polynomial, "implicit shape P(x,y,z) <= 0, e.g. \"x^2+y^2+z^2-1\"");
  auto* v = g->add_option("--volume", volume, "volume file (.vol, .longvol, .nrrd, .raw) digitized by --threshold");
  auto* mf = g->add_option("--mesh-file", mesh_file,
                           "closed triangle mesh (.obj, .ply, .off) voxelized at --resolution N or grid step --h");
  CLI::Option* m = nullptr;
  if (with_mesh) m = g->add_option("--mesh", mesh, "quad mesh of surfels (.obj), vertex/face order kept");
  g->require_option(1);
  (void)s;
  (void)p;
  (void)v;
  (void)m;
  (void)mf;
  h_option = cmd.add_option("--h", h,
                            "grid step (shapes: world units per voxel; volumes: voxel size, default 2/N so that the "
                            "longest side (N voxels) spans 2; mesh files: voxel size in mesh units)")
                 ->check(positive_number());
  cmd.add_option("--resolution", resolution, "mesh files: longest bounding-box side = N voxels")
      ->check(positive_number());
  cmd.add_option("--center", center, "shape centre X Y Z")->expected(3);
  cmd.add_option("--bbox", bbox, "digitization box MIN MAX (reference default -10 10)")->expected(2);
  cmd.add_option("--offset", offset, "extra voxels around the box (reference default 5)")->check(non_negative_number());
  cmd.add_option("--threshold", threshold, "volumes: a voxel is inside when its value > threshold");
  cmd.add_option("--raw-dimensions", raw_dimensions, "raw volumes: NX NY NZ")->expected(3);
}

SurfaceInput SurfaceSource::input() const {
  const bool h_given = h_option && h_option->count() > 0;
  if (resolution > 0 && mesh_file.empty()) throw InputError("--resolution applies to --mesh-file only");
  if (!shape.empty() || !polynomial.empty()) {
    ImplicitShapeInput in;
    in.shape = !shape.empty() ? shape : polynomial;
    in.center = Eigen::Vector3d(center[0], center[1], center[2]);
    in.digitization.h = h;
    in.digitization.min_aabb = bbox[0];
    in.digitization.max_aabb = bbox[1];
    in.digitization.offset = offset;
    return in;
  }
  if (!volume.empty()) {
    VolumeFileInput in;
    in.path = volume;
    in.threshold = threshold;
    if (h_given) in.h = h;  // else world units (docs/io.md): the longest side spans 2
    if (raw_dimensions.size() == 3)
      in.raw_dimensions = Eigen::Vector3i(raw_dimensions[0], raw_dimensions[1], raw_dimensions[2]);
    return in;
  }
  if (!mesh_file.empty()) {
    if (resolution > 0 && h_given) throw InputError("--mesh-file: give either --resolution or --h, not both");
    if (resolution <= 0 && !h_given)
      throw InputError("--mesh-file needs --resolution N (voxels along the longest side) or --h STEP");
    MeshFileInput in;
    in.path = mesh_file;
    in.resolution = resolution;
    if (h_given) in.h = h;
    return in;
  }
  if (!mesh.empty()) {
    QuadMeshInput in;
    in.path = mesh;
    return in;
  }
  throw InputError("no surface source: give --shape, --polynomial, --volume, --mesh-file or --mesh");
}

LoadedSurface SurfaceSource::load() const {
  const SurfaceInput in = input();
  LoadMessages messages;
  messages.warning = [](const std::string& w) { std::cerr << "warning: " << w << "\n"; };
  messages.note = [](const std::string& n) { std::cerr << n << "\n"; };
  return in_cli_terms([&] { return load_surface(in, messages); });
}

OutputUnits OutputUnits::parse(const std::string& name, const LoadedSurface& surface) {
  OutputUnits u;
  if (name == "world") return u;
  if (name != "voxels") throw InputError("--output-units '" + name + "': expected world or voxels");
  u.voxels = true;
  u.frame = surface.frame;
  if (!(u.frame.h() > 0.0)) throw InputError("--output-units voxels: the surface has no grid step");
  return u;
}

SurfelMesh OutputUnits::mesh(const SurfelMesh& m) const {
  if (!voxels) return m;
  SurfelMesh out = m;
  out.positions = frame.to_index(m.positions);
  if (out.h > 0) out.h = frame.length_to_index(m.h);
  return out;
}

std::string SurfaceSource::describe() const { return corrlap::describe(input()); }

void check_regularizable(const SurfelMesh& mesh, const std::string& command) {
  in_cli_terms([&] { corrlap::check_regularizable(mesh); }, command);
}

}  // namespace corrlap::cli

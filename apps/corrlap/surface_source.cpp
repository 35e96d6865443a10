#include "surface_source.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/mesh_voxelization.hpp>
#include <iostream>
#include <sstream>

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

std::optional<ImplicitShape> SurfaceSource::implicit_shape() const {
  const Eigen::Vector3d c(center[0], center[1], center[2]);
  if (!shape.empty()) return make_implicit_shape(shape, c);
  if (!polynomial.empty()) {
    ImplicitShape s = make_implicit_shape(polynomial, c);
    return s;
  }
  return std::nullopt;
}

DigitizationParams SurfaceSource::digitization() const {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = bbox[0];
  p.max_aabb = bbox[1];
  p.offset = offset;
  return p;
}

VoxelGrid SurfaceSource::voxels() const {
  if (resolution > 0 && mesh_file.empty()) throw InputError("--resolution applies to --mesh-file only");
  if (auto s = implicit_shape()) return digitize(*s, digitization());
  if (!volume.empty()) {
    VolumeReadOptions opt;
    opt.threshold = threshold;
    // World units by default (docs/io.md): the longest side spans 2, h = 2 / N; --h overrides.
    const bool h_given = h_option && h_option->count() > 0;
    opt.h = h_given ? h : 0.0;
    opt.centered = true;  // the volume's centre at the origin (docs/io.md)
    if (raw_dimensions.size() == 3)
      opt.raw_dimensions = Eigen::Vector3i(raw_dimensions[0], raw_dimensions[1], raw_dimensions[2]);
    return read_volume_as_voxels(volume, opt);
  }
  if (!mesh_file.empty()) {
    const bool h_given = h_option && h_option->count() > 0;
    if (resolution > 0 && h_given) throw InputError("--mesh-file: give either --resolution or --h, not both");
    if (resolution <= 0 && !h_given)
      throw InputError("--mesh-file needs --resolution N (voxels along the longest side) or --h STEP");
    MeshVoxelizationParams params;
    params.resolution = resolution;
    params.h = h;
    MeshVoxelizationReport report;
    VoxelGrid grid = voxelize_mesh(read_mesh(mesh_file), params, &report);
    for (const std::string& w : report.warnings()) std::cerr << "warning: " << mesh_file << ": " << w << "\n";
    std::cerr << "voxelized " << mesh_file << ": " << report.triangles << " triangles, h = " << report.h << ", grid "
              << report.grid_size.x() << "x" << report.grid_size.y() << "x" << report.grid_size.z() << ", "
              << report.inside_voxels << " voxels inside\n";
    return grid;
  }
  throw InputError("no voxel source: give --shape, --polynomial, --volume or --mesh-file");
}

SurfelMesh SurfaceSource::surface() const {
  if (!mesh.empty()) return to_surfel_mesh(read_mesh(mesh), "mesh file '" + mesh + "'");
  return extract_surface(voxels());
}

LoadedSurface SurfaceSource::load() const {
  LoadedSurface s;
  s.shape = implicit_shape();
  if (!mesh.empty()) {
    s.mesh = surface();
    return s;
  }
  s.grid = voxels();
  if (s.grid->count() == 0) throw InputError("the volume is empty: no voxel is inside (" + describe() + ")");
  // A volume's box is the file's [0, size - 1] - shift, padded by one voxel (read_volume_as_voxels).
  if (!volume.empty()) s.voxel_shift = -s.grid->lower() - Eigen::Vector3i::Ones();
  s.mesh = extract_surface(*s.grid);
  return s;
}

OutputUnits OutputUnits::parse(const std::string& name, const LoadedSurface& surface) {
  OutputUnits u;
  if (name == "world") return u;
  if (name != "voxels") throw InputError("--output-units '" + name + "': expected world or voxels");
  u.voxels = true;
  u.h = surface.mesh.grid_step();
  u.shift = surface.voxel_shift.cast<double>();
  if (!(u.h > 0.0)) throw InputError("--output-units voxels: the surface has no grid step");
  return u;
}

SurfelMesh OutputUnits::mesh(const SurfelMesh& m) const {
  if (!voxels) return m;
  SurfelMesh out = m;
  out.positions = (m.positions / h).rowwise() + shift.transpose();
  if (out.h > 0) out.h = m.h / h;
  return out;
}

std::string SurfaceSource::describe() const {
  std::ostringstream os;
  if (!shape.empty())
    os << shape << ", h=" << h;
  else if (!polynomial.empty())
    os << "\"" << polynomial << "\", h=" << h;
  else if (!volume.empty())
    os << volume << ", threshold " << threshold;
  else if (!mesh_file.empty())
    os << mesh_file << (resolution > 0 ? ", resolution " + std::to_string(resolution) : ", h=" + std::to_string(h));
  else
    os << mesh;
  return os.str();
}

BoundaryCondition boundary_condition(const SurfelMesh& mesh) {
  BoundaryCondition bc;
  for (const int n : build_edges(mesh).faces_per_edge) bc.boundary_edges += n == 1;
  return bc;
}

std::string BoundaryCondition::note() const {
  if (closed()) return {};
  return "the surface is open (" + std::to_string(boundary_edges) +
         " boundary edges): natural (zero Neumann) boundary conditions are used";
}

std::string BoundaryCondition::label() const {
  if (closed()) return "closed";
  return "natural (zero Neumann) on " + std::to_string(boundary_edges) + " boundary edges";
}

void check_regularizable(const SurfelMesh& mesh, bool allow_nonmanifold, const std::string& command) {
  const MeshInfo info = compute_mesh_info(mesh);
  if (!info.closed())
    throw InputError(command + ": the surface is open (" + std::to_string(info.boundary_edges) +
                     " boundary edges); the regularization is defined for closed surfaces");
  if (!info.manifold() && !allow_nonmanifold)
    throw InputError(
        command + ": the surface is not manifold (" + std::to_string(info.nonmanifold_edges) + " non-manifold edges, " +
        std::to_string(info.nonmanifold_vertices) +
        " non-manifold vertices: voxels touching along an edge or a corner); clean the volume "
        "(e.g. a morphological opening; for a voxelized mesh, another --resolution) or give --allow-nonmanifold "
        "to go on anyway");
}

}  // namespace corrlap::cli

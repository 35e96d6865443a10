#include "load_surface.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/mesh_voxelization.hpp>
#include <sstream>

namespace corrlap {
namespace {

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

void check_step(double h, const std::string& what) {
  if (!(h > 0.0) || !std::isfinite(h)) {
    std::ostringstream os;
    os << what << ": grid step h = " << h << " must be positive and finite";
    throw InputError(os.str(), "h");
  }
}

bool is_named_shape(const std::string& name) {
  for (const auto& [shape, polynomial] : named_shapes())
    if (shape == name) return true;
  return false;
}

// The box of read_volume_as_voxels(centered): one voxel of padding, the volume's centre at the origin.
VoxelGrid threshold_array(const VolumeArrayInput& in) {
  const Eigen::Vector3i size = in.size;
  if (size.minCoeff() <= 0) throw InputError("volume: empty array", "volume");
  if (std::size_t(size.x()) * std::size_t(size.y()) * std::size_t(size.z()) != in.values.size())
    throw InputError("volume: " + std::to_string(in.values.size()) + " values for " + std::to_string(size.x()) + "x" +
                         std::to_string(size.y()) + "x" + std::to_string(size.z()) + " voxels",
                     "volume");
  if (in.h) check_step(*in.h, "volume");
  const Eigen::Vector3i shift = volume_centering_shift(size);
  VoxelGrid grid(Eigen::Vector3i::Constant(-1) - shift, size - shift, in.h ? *in.h : unit_size_grid_step(size));
  const double* p = in.values.data();
  std::int64_t inside = 0;
  for (int x = 0; x < size.x(); ++x)
    for (int y = 0; y < size.y(); ++y)
      for (int z = 0; z < size.z(); ++z) {
        const double v = p[(std::int64_t(x) * size.y() + y) * size.z() + z];
        if (std::isnan(v))
          throw InputError("volume: value at [" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                               std::to_string(z) + "] is NaN",
                           "volume");
        if (v > in.threshold) {
          grid.set(x - shift.x(), y - shift.y(), z - shift.z(), true);
          ++inside;
        }
      }
  if (inside == 0) throw InputError("volume: no voxel above the threshold (empty volume)", "threshold");
  return grid;
}

VoxelGrid voxelize_file(const MeshFileInput& in, const LoadMessages& messages) {
  const std::string what = "mesh file '" + in.path + "'";
  if (in.resolution > 0 && in.h) throw InputError(what + ": give either a resolution or a grid step h, not both", "h");
  if (in.resolution <= 0 && !in.h)
    throw InputError(what + " needs a resolution (voxels along the longest side) or a grid step h", "resolution");
  if (in.h) check_step(*in.h, what);
  MeshVoxelizationParams params;
  params.resolution = in.resolution;
  params.h = in.h.value_or(0.0);
  MeshVoxelizationReport report;
  VoxelGrid grid = voxelize_mesh(read_mesh(in.path), params, &report);
  if (messages.warning)
    for (const std::string& w : report.warnings()) messages.warning(in.path + ": " + w);
  if (messages.note) {
    std::ostringstream os;
    os << "voxelized " << in.path << ": " << report.triangles << " triangles, h = " << report.h << ", grid "
       << report.grid_size.x() << "x" << report.grid_size.y() << "x" << report.grid_size.z() << ", "
       << report.inside_voxels << " voxels inside";
    messages.note(os.str());
  }
  return grid;
}

}  // namespace

std::string describe(const SurfaceInput& input) {
  std::ostringstream os;
  std::visit(Overloaded{
                 [&](const ImplicitShapeInput& s) {
                   if (is_named_shape(s.shape))
                     os << s.shape << ", h=" << s.digitization.h;
                   else
                     os << "\"" << s.shape << "\", h=" << s.digitization.h;
                 },
                 [&](const VolumeFileInput& v) { os << v.path << ", threshold " << v.threshold; },
                 [&](const VolumeArrayInput& v) {
                   os << "volume array " << v.size.x() << "x" << v.size.y() << "x" << v.size.z() << ", threshold "
                      << v.threshold;
                 },
                 [&](const MeshFileInput& m) {
                   os << m.path
                      << (m.resolution > 0 ? ", resolution " + std::to_string(m.resolution)
                                           : ", h=" + std::to_string(m.h.value_or(0.0)));
                 },
                 [&](const QuadMeshInput& q) {
                   if (!q.path.empty())
                     os << q.path;
                   else
                     os << "quad mesh (" << q.mesh.num_vertices() << " vertices, " << q.mesh.num_faces() << " faces)";
                 },
             },
             input);
  return os.str();
}

VoxelGrid load_voxels(const SurfaceInput& input, const LoadMessages& messages) {
  return std::visit(Overloaded{
                        [&](const ImplicitShapeInput& s) {
                          check_step(s.digitization.h, "shape '" + s.shape + "'");
                          return digitize(make_implicit_shape(s.shape, s.center), s.digitization);
                        },
                        [&](const VolumeFileInput& v) {
                          VolumeReadOptions opt;
                          opt.threshold = v.threshold;
                          // World units by default (docs/io.md): the longest side spans 2, h = 2 / N.
                          if (v.h) check_step(*v.h, "volume file '" + v.path + "'");
                          opt.h = v.h.value_or(0.0);
                          opt.centered = true;  // the volume's centre at the origin (docs/io.md)
                          opt.raw_dimensions = v.raw_dimensions;
                          return read_volume_as_voxels(v.path, opt);
                        },
                        [&](const VolumeArrayInput& v) { return threshold_array(v); },
                        [&](const MeshFileInput& m) { return voxelize_file(m, messages); },
                        [&](const QuadMeshInput&) -> VoxelGrid {
                          throw InputError(
                              "a quad mesh has no voxels (give an implicit shape, a volume or a mesh "
                              "to voxelize)");
                        },
                    },
                    input);
}

LoadedSurface load_surface(const SurfaceInput& input, const LoadMessages& messages) {
  LoadedSurface s;
  s.description = describe(input);
  if (const auto* q = std::get_if<QuadMeshInput>(&input)) {
    s.mesh = q->path.empty() ? q->mesh : to_surfel_mesh(read_mesh(q->path), "mesh file '" + q->path + "'");
    s.h = s.mesh.grid_step();
    s.frame = VoxelFrame(s.h, Eigen::Vector3d::Zero());
    return s;
  }
  if (const auto* shape = std::get_if<ImplicitShapeInput>(&input))
    s.shape = make_implicit_shape(shape->shape, shape->center);
  s.grid = load_voxels(input, messages);
  if (s.grid->count() == 0)
    throw InputError("the volume is empty: no voxel is inside, so the surface has no surfel (" + s.description + ")");
  // A volume's box is its voxels [0, size - 1] - shift, padded by one voxel (read_volume_as_voxels).
  Eigen::Vector3i shift = Eigen::Vector3i::Zero();
  if (std::holds_alternative<VolumeFileInput>(input) || std::holds_alternative<VolumeArrayInput>(input))
    shift = -s.grid->lower() - Eigen::Vector3i::Ones();
  s.mesh = extract_surface(*s.grid);
  s.h = s.mesh.grid_step();
  s.frame = VoxelFrame(s.h, shift.cast<double>());
  return s;
}

}  // namespace corrlap

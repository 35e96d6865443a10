#include "load_surface.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/io/detail/inside_test.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/mesh_voxelization.hpp>
#include <cstring>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <type_traits>

#include "isotropic_resampling.hpp"

namespace corrlap {
namespace {

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

bool is_named_shape(const std::string& name) {
  for (const auto& [shape, polynomial] : named_shapes())
    if (shape == name) return true;
  return false;
}

using io_detail::InsideTest;
using io_detail::read_value;

// Calls inside(index) for every inside voxel of the box [0, n) of the array, walking the memory in
// its own order (the axis of smallest stride innermost); returns the index of the first NaN met
// instead, if any.
template <class T, bool Swapped, class Inside>
std::optional<Eigen::Vector3i> scan_array(const VolumeArrayInput& in, const Eigen::Vector3i& n,
                                          const InsideTest<T>& test, Inside&& inside) {
  std::array<int, 3> axes = {0, 1, 2};
  // Equal strides (a broadcast): the grid's own order, x innermost, so that a word's 64 bits are
  // set in a row.
  std::sort(axes.begin(), axes.end(), [&](int a, int b) {
    const std::ptrdiff_t sa = std::abs(in.strides[std::size_t(a)]), sb = std::abs(in.strides[std::size_t(b)]);
    return sa > sb || (sa == sb && a > b);
  });
  const auto [a0, a1, a2] = axes;
  const std::ptrdiff_t s0 = in.strides[std::size_t(a0)], s1 = in.strides[std::size_t(a1)],
                       s2 = in.strides[std::size_t(a2)];
  const char* base = static_cast<const char*>(in.data);
  Eigen::Vector3i i;
  for (i[a0] = 0; i[a0] < n[a0]; ++i[a0])
    for (i[a1] = 0; i[a1] < n[a1]; ++i[a1]) {
      const char* row = base + std::ptrdiff_t(i[a0]) * s0 + std::ptrdiff_t(i[a1]) * s1;
      for (i[a2] = 0; i[a2] < n[a2]; ++i[a2]) {
        const T v = read_value<T, Swapped>(row + std::ptrdiff_t(i[a2]) * s2);
        if (InsideTest<T>::is_nan(v)) return i;
        if (test.inside(v)) inside(i);
      }
    }
  return std::nullopt;
}

[[noreturn]] void empty_volume(const InsideRule& rule) {
  const bool label = rule.kind == InsideRule::Kind::Label;
  throw InputError("volume: no voxel " + rule.describe() + " (empty volume); " +
                       (label                                  ? "check the label"
                        : rule.kind == InsideRule::Kind::Above ? "lower the threshold"
                                                               : "check the array"),
                   label ? "label" : "threshold");
}

[[noreturn]] void nan_value(const Eigen::Vector3i& at) {
  throw InputError("volume: value at [" + std::to_string(at.x()) + ", " + std::to_string(at.y()) + ", " +
                       std::to_string(at.z()) + "] is NaN; replace NaN (e.g. numpy.nan_to_num) before digitizing",
                   "volume");
}

void check_inside_rule(const InsideRule& rule, const std::string& what) {
  if (std::isfinite(rule.value)) return;
  std::ostringstream os;
  const bool label = rule.kind == InsideRule::Kind::Label;
  os << what << ": " << (label ? "label" : "threshold") << " = " << rule.value << " must be a finite number";
  throw InputError(os.str(), label ? "label" : "threshold");
}

void check_geometry(const VolumeGeometry& g, const std::string& what) {
  const bool finite = g.spacing.allFinite() && g.origin.allFinite() && g.direction.allFinite();
  if (finite && g.spacing.minCoeff() > 0.0 && std::abs(g.direction.determinant()) > 1e-12) return;
  std::ostringstream os;
  os << what << ": the voxel-to-physical map is degenerate (spacing " << g.spacing.transpose()
     << ", direction determinant " << g.direction.determinant()
     << "): spacings must be positive and the direction matrix invertible";
  throw InputError(os.str(), "affine");
}

// The box of read_volume_as_voxels(centered): one voxel of padding, the volume's centre at the origin.
template <class T, bool Swapped>
VoxelGrid threshold_typed(const VolumeArrayInput& in) {
  const InsideTest<T> test(in.inside);
  if (test.none) empty_volume(in.inside);
  const Eigen::Vector3i size = in.size;
  // A broadcast axis (stride 0) repeats its values: the distinct values are checked first, so that
  // an empty or NaN volume of any announced size is refused before the grid is allocated.
  if (in.strides[0] == 0 || in.strides[1] == 0 || in.strides[2] == 0) {
    Eigen::Vector3i distinct = size;
    for (int a = 0; a < 3; ++a)
      if (in.strides[std::size_t(a)] == 0) distinct[a] = 1;
    bool any_inside = false;
    if (const auto nan = scan_array<T, Swapped>(in, distinct, test, [&](const Eigen::Vector3i&) { any_inside = true; }))
      nan_value(*nan);
    if (!any_inside) empty_volume(in.inside);
  }
  const Eigen::Vector3i shift = volume_centering_shift(size);
  // The constructor checks the grid against the memory budget before allocating it.
  VoxelGrid grid(Eigen::Vector3i::Constant(-1) - shift, size - shift, in.h ? *in.h : unit_size_grid_step(size));
  std::int64_t inside = 0;
  // Voxel (x, y, z) is the grid's (x - shift): its bit is x + 1 of the row (y - shift.y, z - shift.z).
  const auto nan = scan_array<T, Swapped>(in, size, test, [&](const Eigen::Vector3i& i) {
    const int bit = i.x() + 1;
    grid.row(i.y() - shift.y(), i.z() - shift.z())[bit >> 6] |= std::uint64_t{1} << (bit & 63);
    ++inside;
  });
  if (nan) nan_value(*nan);
  if (inside == 0) empty_volume(in.inside);
  return grid;
}

template <class T>
VoxelGrid threshold_as(const VolumeArrayInput& in) {
  return in.byte_swapped && sizeof(T) > 1 ? threshold_typed<T, true>(in) : threshold_typed<T, false>(in);
}

VoxelGrid threshold_array(const VolumeArrayInput& in) {
  const Eigen::Vector3i size = in.size;
  if (size.minCoeff() <= 0)
    throw InputError("volume: empty array (" + std::to_string(size.x()) + "x" + std::to_string(size.y()) + "x" +
                         std::to_string(size.z()) + " voxels)",
                     "volume");
  if (!in.data) throw InputError("volume: no values", "volume");
  check_inside_rule(in.inside, "volume");
  if (in.h) check_grid_step(*in.h, "volume");
  check_geometry(in.geometry, "volume");
  return io_detail::visit_value_type(in.type, [&](auto t) { return threshold_as<decltype(t)>(in); });
}

// Anisotropic voxels become cubes of the finest spacing (isotropic_resampling). `grid` holds the
// file's voxels in the centred, padded box of read_volume_as_voxels; the result is laid out the
// same way, and `geometry` becomes the resampled voxels' map.
VoxelGrid resample_isotropic(const VoxelGrid& grid, VolumeGeometry& geometry, std::optional<double> h) {
  const IsotropicResampling resampling = isotropic_resampling(grid.size() - Eigen::Vector3i::Constant(2), geometry, h);
  // The constructor checks the grid against the memory budget before allocating it.
  VoxelGrid out(resampling.lower(), resampling.upper(), resampling.h);
  resample_voxels(grid, resampling, out);
  geometry = resampling.geometry;
  return out;
}

// The voxels of a volume input, centred, cubic, with their index -> physical map.
VoxelGrid volume_voxels(const SurfaceInput& input, VolumeGeometry& geometry, double* anisotropy = nullptr) {
  VoxelGrid grid;
  std::optional<double> h;
  if (const auto* v = std::get_if<VolumeFileInput>(&input)) {
    VolumeReadOptions opt;
    check_inside_rule(v->inside, "volume file '" + v->path + "'");
    opt.inside = v->inside;
    // World units by default (docs/io.md): the longest side spans 2, h = 2 / N.
    if (v->h) check_grid_step(*v->h, "volume file '" + v->path + "'");
    opt.h = v->h.value_or(0.0);
    opt.centered = true;  // the volume's centre at the origin (docs/io.md)
    opt.raw_dimensions = v->raw_dimensions;
    grid = read_volume_as_voxels(v->path, opt, &geometry);
    check_geometry(geometry, "volume file '" + v->path + "'");
    h = v->h;
  } else {
    const auto& a = std::get<VolumeArrayInput>(input);
    grid = threshold_array(a);
    geometry = a.geometry;
    h = a.h;
  }
  if (geometry.isotropic()) return grid;
  if (anisotropy) *anisotropy = geometry.spacing.maxCoeff() / geometry.spacing.minCoeff();
  return resample_isotropic(grid, geometry, h);
}

VoxelGrid voxelize_file(const MeshFileInput& in, const LoadMessages& messages) {
  const std::string what = "mesh file '" + in.path + "'";
  if (in.resolution > 0 && in.h) throw InputError(what + ": give either a resolution or a grid step h, not both", "h");
  if (in.resolution <= 0 && !in.h)
    throw InputError(what + " needs a resolution (voxels along the longest side) or a grid step h", "resolution");
  if (in.h) check_grid_step(*in.h, what);
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

void check_grid_step(double h, const std::string& what) {
  if (!(h > 0.0) || !std::isfinite(h)) {
    std::ostringstream os;
    os << what << ": grid step h = " << h << " must be positive and finite";
    throw InputError(os.str(), "h");
  }
}

VolumeArrayInput VolumeArrayInput::c_order(std::span<const double> values, const Eigen::Vector3i& size) {
  if (size.minCoeff() < 0 || std::size_t(size.x()) * std::size_t(size.y()) * std::size_t(size.z()) != values.size())
    throw InputError("volume: " + std::to_string(values.size()) + " values for " + std::to_string(size.x()) + "x" +
                         std::to_string(size.y()) + "x" + std::to_string(size.z()) + " voxels",
                     "volume");
  VolumeArrayInput in;
  in.size = size;
  in.data = values.data();
  in.type = VoxelValueType::Float64;
  const auto z = std::ptrdiff_t(sizeof(double));
  in.strides = {z * size.y() * size.z(), z * size.z(), z};
  return in;
}

std::string describe(const SurfaceInput& input) {
  std::ostringstream os;
  std::visit(Overloaded{
                 [&](const ImplicitShapeInput& s) {
                   if (is_named_shape(s.shape))
                     os << s.shape << ", h=" << s.digitization.h;
                   else
                     os << "\"" << s.shape << "\", h=" << s.digitization.h;
                 },
                 [&](const VolumeFileInput& v) { os << v.path << ", inside: " << v.inside.describe(); },
                 [&](const VolumeArrayInput& v) {
                   os << "volume array " << v.size.x() << "x" << v.size.y() << "x" << v.size.z()
                      << ", inside: " << v.inside.describe();
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
                          check_grid_step(s.digitization.h, "shape '" + s.shape + "'");
                          return digitize(make_implicit_shape(s.shape, s.center), s.digitization);
                        },
                        [&](const VolumeFileInput&) {
                          VolumeGeometry geometry;
                          return volume_voxels(input, geometry);
                        },
                        [&](const VolumeArrayInput&) {
                          VolumeGeometry geometry;
                          return volume_voxels(input, geometry);
                        },
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
  const bool volume = std::holds_alternative<VolumeFileInput>(input) || std::holds_alternative<VolumeArrayInput>(input);
  VolumeGeometry geometry;
  s.grid = volume ? volume_voxels(input, geometry, &s.anisotropy) : load_voxels(input, messages);
  if (s.grid->count() == 0)
    throw InputError("the volume is empty: no voxel is inside, so the surface has no surfel (" + s.description + ")");
  s.mesh = extract_surface(*s.grid);
  s.h = s.mesh.grid_step();
  s.frame = volume ? volume_voxel_frame(s.grid->lower(), s.h, geometry) : VoxelFrame(s.h, Eigen::Vector3d::Zero());
  face_components(s.mesh, s.components);
  return s;
}

VoxelFrame volume_voxel_frame(const Eigen::Vector3i& lower, double h, const VolumeGeometry& geometry) {
  const Eigen::Vector3i shift = -lower - Eigen::Vector3i::Ones();
  return VoxelFrame(h, shift.cast<double>(), geometry);
}

Eigen::MatrixX3d VoxelFrame::to_physical(const Eigen::MatrixX3d& world) const {
  if (!geometry_) return world;
  const Eigen::MatrixX3d index = to_index(world);
  const Eigen::Matrix3d linear = geometry_->direction * geometry_->spacing.asDiagonal();
  return Eigen::MatrixX3d((index * linear.transpose()).rowwise() + geometry_->origin.transpose());
}

double VoxelFrame::length_to_physical(double length) const {
  if (!geometry_) return length;
  // Cubic voxels (load_surface resamples anisotropic ones) along unit axes: one scale.
  return length / h_ * geometry_->spacing.x();
}

Eigen::MatrixX3d VoxelFrame::normals_to_physical(const Eigen::MatrixX3d& normals) const {
  if (!geometry_) return normals;
  // Normals map by the inverse transpose of the linear part (the identity up to scale for axes
  // that are orthonormal, a rotation).
  const Eigen::Matrix3d linear = geometry_->direction * geometry_->spacing.asDiagonal();
  Eigen::MatrixX3d out = normals * linear.inverse();
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    const double n = out.row(i).norm();
    if (n > 0) out.row(i) /= n;
  }
  return out;
}

bool VoxelFrame::mirrors() const { return geometry_ && geometry_->direction.determinant() < 0.0; }

Eigen::Matrix3d VoxelFrame::space_change_to(PhysicalSpace to) const {
  if (to != space() && space() == PhysicalSpace::Unknown)
    throw InputError(std::string("the input's physical space is unknown (") +
                         (geometry_ ? "the volume file names none: NIfTI is RAS, MetaImage LPS, an NRRD names its "
                                      "'space'; .vol, .raw, binvox, .vox, .npy and TIFF have none"
                                    : "shapes, mesh files and arrays have no anatomical space") +
                         ")",
                     "space");
  return space_change(space(), to);
}

std::vector<double> volume_labels(const VolumeData& volume) {
  std::set<double> labels;
  const std::size_t n = std::size_t(volume.size.x()) * std::size_t(volume.size.y()) * std::size_t(volume.size.z());
  io_detail::visit_value_type(volume.type, [&](auto t) {
    using T = decltype(t);
    const std::size_t bytes = value_bytes(volume.type);
    if (volume.bytes.size() < n * bytes) throw InputError("volume: fewer values than voxels", "volume");
    for (std::size_t i = 0; i < n; ++i) {
      const T v = read_value<T, false>(volume.bytes.data() + i * bytes);
      if (InsideTest<T>::is_nan(v)) {
        const std::size_t x = i % std::size_t(volume.size.x()), yz = i / std::size_t(volume.size.x());
        nan_value(
            Eigen::Vector3i(int(x), int(yz % std::size_t(volume.size.y())), int(yz / std::size_t(volume.size.y()))));
      }
      if (v == T(0)) continue;
      labels.insert(double(v));
      if (labels.size() > kMaxVolumeLabels)
        throw InputError("volume: more than " + std::to_string(kMaxVolumeLabels) +
                             " distinct nonzero values: this looks like a grey-level image, not a segmentation; "
                             "give --threshold T (inside: value > T) instead of --labels all",
                         "labels");
    }
  });
  if (labels.empty()) throw InputError("volume: no nonzero value, so no label (empty segmentation)", "labels");
  return {labels.begin(), labels.end()};
}

std::vector<double> volume_labels(const std::string& path) {
  try {
    return volume_labels(read_volume_data(path));
  } catch (const InputError& e) {
    if (dynamic_cast<const IoError*>(&e)) throw;
    throw InputError("'" + path + "': " + std::string(e.what()), "labels");
  }
}

VolumeArrayInput volume_array(const VolumeData& volume, const InsideRule& inside, std::optional<double> h) {
  VolumeArrayInput in;
  in.size = volume.size;
  in.data = volume.bytes.data();
  in.type = volume.type;
  const auto b = std::ptrdiff_t(value_bytes(volume.type));
  in.strides = {b, b * volume.size.x(), b * volume.size.x() * volume.size.y()};  // i fastest
  in.inside = inside;
  in.geometry = volume.geometry;
  in.h = h;
  return in;
}

}  // namespace corrlap

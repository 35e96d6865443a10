// Voxels -> digital surface (the library's load_surface), and mesh files: digitize, digitize_volume,
// read_mesh, write_mesh.
#include <pybind11/stl.h>

#include <cctype>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_checks.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <limits>
#include <optional>
#include <span>

#include "bindings.hpp"
#include "convert.hpp"

namespace corrlap::python {
namespace {

py::tuple surface_of(const SurfaceInput& input) {
  LoadedSurface surface;
  {
    py::gil_scoped_release release;
    surface = load_surface(input);
  }
  return py::make_tuple(to_numpy(surface.mesh.positions), faces_to_numpy(surface.mesh.faces));
}

ImplicitShapeInput shape_input(const std::string& shape, double h, double bbox_min, double bbox_max, int offset,
                               py::handle center) {
  const Eigen::MatrixX3d c = points_arg(center, "center", 1);
  ImplicitShapeInput in;
  in.shape = shape;
  in.center = c.row(0).transpose();
  in.digitization = {.h = h, .min_aabb = bbox_min, .max_aabb = bbox_max, .offset = offset};
  return in;
}

// The array as the library's in-memory volume, read where it is: its own dtype, strides and byte
// order (no converted copy, whatever its size). `keep` holds the array alive while it is read.
VolumeArrayInput array_input(py::handle volume, std::optional<double> h, const InsideRule& inside, py::array& keep) {
  keep = numeric_array(volume, "volume", /*allow_bool=*/true);
  if (keep.ndim() != 3)
    throw py::value_error("volume: expected a 3D array, got " + std::to_string(keep.ndim()) + " dimensions");
  VolumeArrayInput in;
  in.type = voxel_value_type(keep.dtype(), "volume");
  for (int a = 0; a < 3; ++a) {
    // The grid pads each side by a voxel: its int coordinates must hold size + 2.
    if (keep.shape(a) > std::numeric_limits<int>::max() - 2)
      throw py::value_error("volume: axis " + std::to_string(a) + " has " + std::to_string(keep.shape(a)) +
                            " voxels, more than a voxel grid holds");
    in.size[a] = int(keep.shape(a));
    in.strides[std::size_t(a)] = keep.strides(a);
  }
  in.data = keep.data();
  in.byte_swapped = !keep.dtype().attr("isnative").cast<bool>();
  in.inside = inside;
  in.h = h;
  return in;
}

// "RAS", "LPS" or "LAS" (any case) as a space; "" for none (Unknown). ValueError otherwise.
PhysicalSpace space_arg(const std::string& name, const char* what) {
  std::string upper = name;
  for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  if (upper.empty()) return PhysicalSpace::Unknown;
  for (const PhysicalSpace s : {PhysicalSpace::RAS, PhysicalSpace::LPS, PhysicalSpace::LAS})
    if (upper == space_name(s)) return s;
  throw py::value_error(std::string(what) + "='" + name + "': expected 'RAS', 'LPS', 'LAS' or None");
}

// A 4 by 4 affine (nibabel's, index -> physical) as spacing, unit direction columns and origin.
VolumeGeometry geometry_arg(py::handle affine) {
  bool was_vector = false;
  const Eigen::MatrixXd a = matrix_arg(affine, "affine", 4, was_vector);
  if (was_vector || a.cols() != 4) throw py::value_error("affine: expected a 4 by 4 array");
  if (!a.allFinite()) throw py::value_error("affine: the values must be finite");
  VolumeGeometry g;
  for (int c = 0; c < 3; ++c) {
    g.spacing[c] = a.block<3, 1>(0, c).norm();
    if (!(g.spacing[c] > 0.0))
      throw py::value_error("affine: column " + std::to_string(c) + " is zero (a voxel side of length 0)");
    g.direction.col(c) = a.block<3, 1>(0, c) / g.spacing[c];
  }
  g.origin = a.block<3, 1>(0, 3);
  return g;
}

InsideRule inside_arg(std::optional<double> label, std::optional<double> threshold) {
  if (label && threshold) throw py::value_error("label, threshold: give one of them (or neither: every nonzero voxel)");
  if (label) return InsideRule::label(*label);
  if (threshold) return InsideRule::above(*threshold);
  return InsideRule::nonzero();
}

py::array volume_to_numpy(VolumeData&& volume) {
  // The file's i fastest is numpy's Fortran order of an array indexed [i, j, k].
  const py::dtype dtype(value_type_name(volume.type));
  const auto b = py::ssize_t(value_bytes(volume.type));
  const std::vector<py::ssize_t> shape = {volume.size.x(), volume.size.y(), volume.size.z()};
  const std::vector<py::ssize_t> strides = {b, b * volume.size.x(), b * volume.size.x() * volume.size.y()};
  auto* owner = new VolumeData(std::move(volume));
  py::capsule free(owner, [](void* p) { delete static_cast<VolumeData*>(p); });
  return py::array(dtype, shape, strides, owner->bytes.data(), free);
}

}  // namespace

VoxelGrid shape_voxels(const std::string& shape, double h, double bbox_min, double bbox_max, int offset,
                       py::handle center) {
  const ImplicitShapeInput in = shape_input(shape, h, bbox_min, bbox_max, offset, center);
  py::gil_scoped_release release;
  return load_voxels(in);
}

VoxelGrid array_voxels(py::handle volume, std::optional<double> h, double threshold) {
  py::array values;
  const VolumeArrayInput in = array_input(volume, h, InsideRule::above(threshold), values);
  py::gil_scoped_release release;
  return load_voxels(in);
}

void bind_surface(py::module_& m) {
  m.def(
      "digitize",
      [](const std::string& shape, double h, double bbox_min, double bbox_max, int offset, py::handle center) {
        return surface_of(shape_input(shape, h, bbox_min, bbox_max, offset, center));
      },
      py::arg("shape"), py::arg("h"), py::arg("bbox_min"), py::arg("bbox_max"), py::arg("offset"), py::arg("center"));
  m.def(
      "digitize_volume",
      [](py::handle volume, std::optional<double> h, double threshold) {
        py::array values;
        return surface_of(array_input(volume, h, InsideRule::above(threshold), values));
      },
      py::arg("volume"), py::arg("h"), py::arg("threshold"));
  m.def(
      "read_volume",
      [](const std::string& path, const std::string& space) {
        VolumeData volume;
        {
          py::gil_scoped_release release;
          volume = read_volume_data(path);
        }
        const PhysicalSpace wanted = space_arg(space, "space");
        if (space.empty()) {
          // the file's own space
        } else if (volume.geometry.space == PhysicalSpace::Unknown) {
          throw py::value_error("space='" + space + "': the volume file '" + path +
                                "' names no anatomical space (NIfTI is RAS, MetaImage LPS, an NRRD names its "
                                "'space'); omit space to get the file's own affine");
        } else {
          volume.geometry = volume.geometry.in_space(wanted);
        }
        const Eigen::Matrix4d affine = volume.geometry.affine();
        const py::object name = volume.geometry.space == PhysicalSpace::Unknown
                                    ? py::object(py::none())
                                    : py::object(py::str(space_name(volume.geometry.space)));
        return py::make_tuple(volume_to_numpy(std::move(volume)), to_numpy(Eigen::MatrixXd(affine)), name);
      },
      py::arg("path"), py::arg("space"));
  m.def(
      "write_volume",
      [](const std::string& path, py::handle array, py::handle affine, const std::string& space) {
        // The Python side passes a native-order Fortran array: its bytes are the file's order.
        py::array values = numeric_array(array, "array", /*allow_bool=*/true);
        if (values.ndim() != 3)
          throw py::value_error("array: expected a 3D array, got " + std::to_string(values.ndim()) + " dimensions");
        VolumeData volume;
        volume.type = voxel_value_type(values.dtype(), "array");
        for (int a = 0; a < 3; ++a) {
          if (values.shape(a) > std::numeric_limits<int>::max())
            throw py::value_error("array: axis " + std::to_string(a) + " is too long for a volume file");
          volume.size[a] = int(values.shape(a));
        }
        const auto* begin = static_cast<const std::uint8_t*>(values.data());
        volume.bytes.assign(begin, begin + values.nbytes());
        if (!affine.is_none()) volume.geometry = geometry_arg(affine);
        volume.geometry.space = space_arg(space, "space");
        py::gil_scoped_release release;
        write_volume_data(path, volume);
      },
      py::arg("path"), py::arg("array"), py::arg("affine"), py::arg("space"));
  m.def(
      "regularize_volume",
      [](py::handle volume, std::optional<double> label, std::optional<double> threshold, py::handle affine,
         std::optional<double> h, const std::string& method, const py::dict& params, std::optional<double> alpha0,
         std::optional<double> curvature_radius, std::optional<double> curvature_spacing, std::optional<double> size,
         const std::string& solver, const py::dict& solver_options, std::optional<double> solve_accuracy,
         const std::string& space, std::optional<std::string> thin_parts, const py::object& progress) {
        const InsideRule inside = inside_arg(label, threshold);
        const ProgressLine progress_line = progress_arg(progress);
        NormalRequest ii_normals;  // II from the voxels, with the voxel defaults but for the thin parts asked
        if (const std::optional<bool> shrink = thin_parts_arg(thin_parts))
          ii_normals.ii = default_ii_params(/*implicit_shape=*/false, {}, {}, shrink);
        const PhysicalSpace wanted = space_arg(space, "space");
        py::array values;
        SurfaceInput input;
        if (py::isinstance<py::str>(volume)) {
          if (!affine.is_none())
            throw py::value_error("affine: a volume file has its own geometry; give affine with an array only");
          VolumeFileInput in;
          in.path = volume.cast<std::string>();
          in.inside = inside;
          in.h = h;
          input = in;
        } else {
          if (wanted != PhysicalSpace::Unknown)
            throw py::value_error("space='" + space +
                                  "': an array's affine names no anatomical space; give the affine in the space "
                                  "wanted (space converts a volume file's own)");
          VolumeArrayInput in = array_input(volume, h, inside, values);
          if (!affine.is_none()) in.geometry = geometry_arg(affine);
          input = in;
        }
        RegularizationOptions o = regularization_options_arg(
            method, params, alpha0, curvature_radius, curvature_spacing, size, solver, solver_options, solve_accuracy);
        o.report_stage = progress_line;
        ii_normals.progress = tenths_progress("ii normals", progress_line);
        std::vector<std::string> warnings;
        SurfelMesh out;
        {
          py::gil_scoped_release release;
          check_regularization_options(o);
          // As `corrlap regularize --volume`: II normals from the voxels, outputs in physical coordinates.
          const LoadedSurface surface = load_surface(input);
          // Before the computation: a space the file does not name is refused at once.
          Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();
          if (wanted != PhysicalSpace::Unknown) {
            try {
              flip = surface.frame.space_change_to(wanted);
            } catch (const InputError& e) {
              throw InputError("space='" + space + "': " + e.what() + "; omit space to get the file's own coordinates",
                               "space");
            }
          }
          check_regularizable(surface.mesh);
          check_regularization_options(surface.mesh, o);
          const NormalFields normals = resolve_normals(surface, NormalKind::Vertex, ii_normals, "regularize_volume");
          const RegularizedSurface r = regularize_surface(surface, normals, o);
          warnings = r.warnings;
          out = r.mesh;
          out.positions = surface.frame.to_physical(r.mesh.positions);
          if (wanted != PhysicalSpace::Unknown) out.positions *= flip.transpose();
          if (surface.frame.mirrors()) out.faces = out.faces.rowwise().reverse().eval();
        }
        py::list w;
        for (const auto& s : warnings) w.append(s);
        return py::make_tuple(to_numpy(out.positions), faces_to_numpy(out.faces), w);
      },
      py::arg("volume"), py::arg("label"), py::arg("threshold"), py::arg("affine"), py::arg("h"), py::arg("method"),
      py::arg("params"), py::arg("alpha0"), py::arg("curvature_radius"), py::arg("curvature_spacing"), py::arg("size"),
      py::arg("solver"), py::arg("solver_options"), py::arg("solve_accuracy"), py::arg("space"), py::arg("thin_parts"),
      py::arg("progress"));
  m.def(
      "read_mesh",
      [](const std::string& path) {
        PolygonMesh mesh;
        {
          py::gil_scoped_release release;
          mesh = read_mesh(path);
        }
        // Quads stay (m, 4); any other single face degree d gives (m, d).
        const Eigen::Index m_faces = Eigen::Index(mesh.faces.size());
        const std::size_t degree = m_faces ? mesh.faces[0].size() : 4;
        py::array_t<std::int64_t> F({m_faces, Eigen::Index(degree)});
        std::int64_t* out = F.mutable_data();
        for (Eigen::Index f = 0; f < m_faces; ++f) {
          const auto face = mesh.faces[std::size_t(f)];
          if (face.size() != degree)
            throw InputError("read_mesh: '" + path + "' mixes faces of " + std::to_string(degree) + " and " +
                             std::to_string(face.size()) + " corners (face " + std::to_string(f) + ")");
          for (std::size_t j = 0; j < degree; ++j) *out++ = face[j];
        }
        return py::make_tuple(to_numpy(mesh.positions), F);
      },
      py::arg("path"));
  m.def(
      "write_mesh",
      [](const std::string& path, py::handle V, py::handle F, const py::dict& vertex_scalars,
         const py::dict& face_scalars, py::object vertex_normals, py::object face_normals) {
        const SurfelMesh mesh = mesh_arg(V, F);
        MeshAttributes attributes;
        for (const auto& [name, values] : vertex_scalars)
          attributes.vertex_scalars[py::str(name)] =
              vector_arg(values, "vertex_scalars['" + std::string(py::str(name)) + "']", mesh.num_vertices());
        for (const auto& [name, values] : face_scalars)
          attributes.face_scalars[py::str(name)] =
              vector_arg(values, "face_scalars['" + std::string(py::str(name)) + "']", mesh.num_faces());
        if (!vertex_normals.is_none())
          attributes.vertex_normals = points_arg(vertex_normals, "vertex_normals", mesh.num_vertices());
        if (!face_normals.is_none())
          attributes.face_normals = points_arg(face_normals, "face_normals", mesh.num_faces());
        py::gil_scoped_release release;
        write_mesh(path, mesh, attributes);
      },
      py::arg("path"), py::arg("V"), py::arg("F"), py::arg("vertex_scalars"), py::arg("face_scalars"),
      py::arg("vertex_normals"), py::arg("face_normals"));
}

}  // namespace corrlap::python

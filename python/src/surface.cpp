// Voxels -> digital surface (the library's load_surface), and mesh files: digitize, digitize_volume,
// read_mesh, write_mesh.
#include <pybind11/stl.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/pipeline/load_surface.hpp>
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
VolumeArrayInput array_input(py::handle volume, std::optional<double> h, double threshold, py::array& keep) {
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
  in.threshold = threshold;
  in.h = h;
  return in;
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
  const VolumeArrayInput in = array_input(volume, h, threshold, values);
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
        return surface_of(array_input(volume, h, threshold, values));
      },
      py::arg("volume"), py::arg("h"), py::arg("threshold"));
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

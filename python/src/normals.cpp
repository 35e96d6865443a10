// Normal fields and curvature: true_normals, ii_normals (from a shape or a volume), curvature.
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/surface/extract_surface.hpp>

#include "bindings.hpp"
#include "convert.hpp"

namespace corrlap::python {
namespace {

bool at_vertices(const std::string& at) {
  if (at != "faces" && at != "vertices") throw py::value_error("at: '" + at + "': expected 'faces' or 'vertices'");
  return at == "vertices";
}

// II normals need the surfels (which voxels each face separates): the mesh is extracted again
// from the voxels and must be the given one, as digitize returned it.
py::array_t<double> ii_normals(const VoxelGrid& grid, py::handle V, py::handle F, double k, double alpha,
                               const std::string& at) {
  const bool vertices = at_vertices(at);
  const SurfelMesh given = mesh_arg(V, F, 0.0);
  Eigen::MatrixX3d n;
  {
    py::gil_scoped_release release;
    const SurfelMesh mesh = extract_surface(grid);
    if (mesh.faces != given.faces || mesh.positions != given.positions)
      throw InputError("V, F: not the surface of these voxels (" + std::to_string(mesh.num_vertices()) +
                       " vertices and " + std::to_string(mesh.num_faces()) + " faces expected, " +
                       std::to_string(given.num_vertices()) + " and " + std::to_string(given.num_faces()) +
                       " given): pass the V, F that digitize returned for the same shape or volume and parameters");
    n = ii_face_normals(grid, mesh, {.k = k, .alpha = alpha});
    if (vertices) n = vertex_normals_from_face_normals(n, mesh.faces, mesh.num_vertices());
  }
  return to_numpy(n);
}

}  // namespace

void bind_normals(py::module_& m) {
  m.def(
      "true_normals",
      [](const std::string& shape, py::handle V, py::handle F, const std::string& at, py::handle center) {
        const bool vertices = at_vertices(at);
        const Eigen::MatrixX3d c = points_arg(center, "center", 1);
        const ImplicitShape s = make_implicit_shape(shape, c.row(0).transpose());
        const SurfelMesh mesh = mesh_arg(V, F, 0.0);
        Eigen::MatrixX3d n;
        {
          py::gil_scoped_release release;
          // Vertex normals as --normals true gives them: the normalized sum of the face normals.
          n = vertices ? true_vertex_normals_from_faces(s, mesh) : true_face_normals(s, mesh);
        }
        return to_numpy(n);
      },
      py::arg("shape"), py::arg("V"), py::arg("F"), py::arg("at"), py::arg("center"));
  m.def(
      "ii_normals_shape",
      [](const std::string& shape, py::handle V, py::handle F, double h, double bbox_min, double bbox_max, int offset,
         py::handle center, double k, double alpha, const std::string& at) {
        return ii_normals(shape_voxels(shape, h, bbox_min, bbox_max, offset, center), V, F, k, alpha, at);
      },
      py::arg("shape"), py::arg("V"), py::arg("F"), py::arg("h"), py::arg("bbox_min"), py::arg("bbox_max"),
      py::arg("offset"), py::arg("center"), py::arg("k"), py::arg("alpha"), py::arg("at"));
  m.def(
      "ii_normals_volume",
      [](py::handle volume, py::handle V, py::handle F, double h, double threshold, double k, double alpha,
         const std::string& at) { return ii_normals(array_voxels(volume, h, threshold), V, F, k, alpha, at); },
      py::arg("volume"), py::arg("V"), py::arg("F"), py::arg("h"), py::arg("threshold"), py::arg("k"), py::arg("alpha"),
      py::arg("at"));
  m.def(
      "curvature",
      [](py::handle V, py::handle F, py::object face_normals, py::object vertex_normals, double radius,
         const std::string& at, bool constant) {
        const bool vertices = at_vertices(at);
        if (!(radius >= 0.0)) throw py::value_error("radius: must be >= 0");
        const SurfelMesh mesh = mesh_arg(V, F, 0.0);
        Eigen::MatrixX3d fn, vn;
        if (!face_normals.is_none()) fn = points_arg(face_normals, "face_normals", mesh.num_faces());
        if (!vertex_normals.is_none()) vn = points_arg(vertex_normals, "vertex_normals", mesh.num_vertices());
        if (constant && fn.rows() == 0) throw py::value_error("face_normals: constant=True needs face normals");
        if (!constant && fn.rows() == 0 && vn.rows() == 0)
          throw py::value_error("face_normals, vertex_normals: give one of them");
        CurvatureEstimates e;
        {
          py::gil_scoped_release release;
          // As `corrlap curvature --normals`: interpolated vertex normals, the normalized sum of the
          // face normals unless given; constant face normals on request.
          if (!constant && vn.rows() == 0) vn = vertex_normals_from_face_normals(fn, mesh.faces, mesh.num_vertices());
          const CorrectedCurvature cc =
              constant ? CorrectedCurvature::constant(mesh, fn) : CorrectedCurvature::interpolated(mesh, vn);
          e = vertices ? cc.at_vertices(radius) : cc.at_faces(radius);
        }
        return py::make_tuple(to_numpy(e.H), to_numpy(e.G), to_numpy(e.k1), to_numpy(e.k2), to_numpy(e.d1),
                              to_numpy(e.d2));
      },
      py::arg("V"), py::arg("F"), py::arg("face_normals"), py::arg("vertex_normals"), py::arg("radius"), py::arg("at"),
      py::arg("constant"));
}

}  // namespace corrlap::python

// Surface regularization of paper §4.1 (docs/regularization.md): regularize(V, F, normals, ...) -> P.
#include <corrlap/core/error.hpp>
#include <corrlap/regularization/regularize_surface.hpp>

#include "bindings.hpp"
#include "convert.hpp"

namespace corrlap::python {

void bind_regularization(py::module_& m) {
  m.def(
      "regularize",
      [](py::handle V, py::handle F, py::handle face_normals, py::handle vertex_normals, const std::string& method,
         double h, const py::dict& params, double alpha0, py::object curvature_radius, py::object size,
         const std::string& solver, const py::dict& solver_options) {
        const SurfelMesh mesh = mesh_arg(V, F, h);
        NormalFields normals;
        if (!face_normals.is_none()) normals.face = points_arg(face_normals, "face_normals", mesh.num_faces());
        if (!vertex_normals.is_none())
          normals.vertex = points_arg(vertex_normals, "vertex_normals", mesh.num_vertices());
        if (!normals.has_face() && !normals.has_vertex())
          throw py::value_error("face_normals, vertex_normals: give one of them");
        RegularizationOptions o;
        o.method = method;
        o.method_params = config_arg(params, method);
        o.alpha0 = alpha0;
        if (!curvature_radius.is_none()) o.curvature_radius = curvature_radius.cast<double>();
        if (!size.is_none()) o.size = size.cast<double>();
        o.solver = config_arg(solver_options, solver);
        o.solver.set("solver", solver);
        const RegularizedSurface r = [&] {
          py::gil_scoped_release release;
          // As `corrlap regularize`: vertex normals are the normalized sum of the face normals unless given.
          if (!normals.has_vertex())
            normals.vertex = vertex_normals_from_face_normals(normals.face, mesh.faces, mesh.num_vertices());
          return regularize_surface(mesh, normals, o);
        }();
        py::list warnings;
        for (const auto& w : r.warnings) warnings.append(w);
        return py::make_tuple(to_numpy(r.mesh.positions), to_numpy(r.H), warnings);
      },
      py::arg("V"), py::arg("F"), py::arg("face_normals"), py::arg("vertex_normals"), py::arg("method"), py::arg("h"),
      py::arg("params"), py::arg("alpha0"), py::arg("curvature_radius"), py::arg("size"), py::arg("solver"),
      py::arg("solver_options"));
}

}  // namespace corrlap::python

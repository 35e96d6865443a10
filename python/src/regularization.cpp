// Surface regularization of paper §4.1 (docs/regularization.md): regularize(V, F, normals, ...) -> P.
#include <corrlap/core/error.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/pipeline/surface_checks.hpp>
#include <corrlap/regularization/regularize_surface.hpp>

#include "bindings.hpp"
#include "convert.hpp"

namespace corrlap::python {

RegularizationOptions regularization_options_arg(const std::string& method, const py::dict& params,
                                                 std::optional<double> alpha0, std::optional<double> curvature_radius,
                                                 std::optional<double> curvature_spacing, std::optional<double> size,
                                                 const std::string& solver, const py::dict& solver_options,
                                                 std::optional<double> solve_accuracy) {
  RegularizationOptions o;
  if (solve_accuracy) o.solve_accuracy = *solve_accuracy;  // checked with the rest (check_regularization_options)
  o.method = method;
  o.method_params = config_arg(params, method);
  o.alpha0_auto = !alpha0;
  if (alpha0) o.alpha0 = *alpha0;
  o.curvature_radius = curvature_radius;
  if (curvature_spacing) o.curvature_spacing = *curvature_spacing;
  o.size = size;
  o.solver = config_arg(solver_options, solver);
  o.solver.set("solver", solver);
  return o;
}

void bind_regularization(py::module_& m) {
  // The library's default radii, for the docstrings (python/corrlap/__init__.py) and the tests.
  m.attr("VOXEL_II_RADIUS") = kVoxelIIRadius;
  m.attr("VOXEL_MIN_CURVATURE_RADIUS") = kVoxelMinCurvatureRadius;
  m.attr("CURVATURE_RADIUS_FRACTION") = kCurvatureRadiusFraction;
  m.attr("CURVATURE_SITE_SPACING") = kCurvatureSiteSpacing;
  m.attr("SOLVE_ACCURACY") = kRegularizationSolveAccuracy;
  m.attr("ALPHA0_START") = RegularizationOptions{}.alpha0;
  m.def(
      "regularize",
      [](py::handle V, py::handle F, py::handle face_normals, py::handle vertex_normals, const std::string& method,
         std::optional<double> h, const py::dict& params, std::optional<double> alpha0,
         std::optional<double> curvature_radius, std::optional<double> curvature_spacing, std::optional<double> size,
         const std::string& solver, const py::dict& solver_options, std::optional<double> solve_accuracy,
         const py::object& progress) {
        const SurfelMesh mesh = mesh_arg(V, F, h);
        const NormalRequest request = given_normals_arg(face_normals, vertex_normals, mesh);
        if (request.face_normals.rows() == 0 && request.vertex_normals.rows() == 0)
          throw py::value_error("face_normals, vertex_normals: give one of them");
        RegularizationOptions o = regularization_options_arg(
            method, params, alpha0, curvature_radius, curvature_spacing, size, solver, solver_options, solve_accuracy);
        o.report_stage = progress_arg(progress);
        const RegularizedSurface r = [&] {
          py::gil_scoped_release release;
          // As `corrlap regularize`: the same surface policy, and vertex normals the normalized sum of
          // the face normals unless given.
          check_regularizable(mesh);
          const NormalFields normals =
              resolve_normals(mesh, NormalKind::Vertex, request, nullptr, nullptr, "regularize");
          return regularize_surface(mesh, normals, o);
        }();
        py::list warnings;
        for (const auto& w : r.warnings) warnings.append(w);
        return py::make_tuple(to_numpy(r.mesh.positions), to_numpy(r.H), warnings);
      },
      py::arg("V"), py::arg("F"), py::arg("face_normals"), py::arg("vertex_normals"), py::arg("method"), py::arg("h"),
      py::arg("params"), py::arg("alpha0"), py::arg("curvature_radius"), py::arg("curvature_spacing"), py::arg("size"),
      py::arg("solver"), py::arg("solver_options"), py::arg("solve_accuracy"), py::arg("progress"));
}

}  // namespace corrlap::python

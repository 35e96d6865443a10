// The interactive page of surfaces (render/view_page.hpp): view_page(surfaces, ...) -> str.
#include <corrlap/core/error.hpp>
#include <corrlap/render/view_page.hpp>

#include "bindings.hpp"
#include "convert.hpp"

namespace corrlap::python {

namespace {

// Faces of any one degree d in [3, 255] (the page fans them).
FaceList polygons_arg(py::handle obj, const std::string& name, Eigen::Index num_vertices) {
  const FaceIds ids = face_ids_arg(obj, name, num_vertices, 3, 255, "(m, d) with 3 <= d <= 255 corners per face");
  const std::int64_t* p = ids.data();
  const Eigen::Index m = ids.shape(0), d = ids.shape(1);
  FaceList faces;
  for (Eigen::Index f = 0; f < m; ++f) {
    faces.start_face();
    for (Eigen::Index j = 0; j < d; ++j) faces.add_corner(int(p[f * d + j]));
  }
  return faces;
}

ViewSurface surface_arg(const py::dict& s, std::size_t index) {
  ViewSurface out;
  out.name = py::str(s["name"]);
  const std::string what = "surface " + std::to_string(index) + " ('" + out.name + "')";
  out.mesh.positions = points_arg(s["V"], what + ": V");
  out.mesh.faces = polygons_arg(s["F"], what + ": F", out.mesh.positions.rows());
  out.visible = py::bool_(s["visible"]);
  for (const auto& [name, values] : py::dict(s["vertex_scalars"]))
    out.fields.push_back(
        {py::str(name),
         vector_arg(values, what + ": scalars['" + std::string(py::str(name)) + "']", out.mesh.positions.rows()),
         false});
  for (const auto& [name, values] : py::dict(s["face_scalars"]))
    out.fields.push_back({py::str(name),
                          vector_arg(values, what + ": face_scalars['" + std::string(py::str(name)) + "']",
                                     Eigen::Index(out.mesh.faces.size())),
                          true});
  return out;
}

}  // namespace

void bind_view(py::module_& m) {
  m.def("has_viewer", &has_viewer);
  m.def(
      "view_page",
      [](const py::list& surfaces, const std::string& title, const std::string& initial_field,
         const std::optional<std::string>& layout) {
        std::vector<ViewSurface> s;
        for (std::size_t i = 0; i < surfaces.size(); ++i) s.push_back(surface_arg(surfaces[i].cast<py::dict>(), i));
        ViewOptions o;
        o.title = title;
        o.initial_field = initial_field;
        if (layout) o.layout = *layout;
        std::string page;
        {
          py::gil_scoped_release release;
          page = view_page(s, o);
        }
        return py::bytes(page);
      },
      py::arg("surfaces"), py::arg("title"), py::arg("initial_field"), py::arg("layout"));
}

}  // namespace corrlap::python

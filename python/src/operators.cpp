// Operators: laplacian(V, F, method, normals, params) through the discretization registry, as
// `corrlap operators` assembles them, and the bare C++ timing used by bench/bench_python.py.
#include <chrono>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/registry.hpp>

#include "bindings.hpp"
#include "convert.hpp"

namespace corrlap::python {
namespace {

// The normals a method needs, from the library's resolve_normals as the CLI gets them (docs/math.md
// §1.5): face normals as given; vertex normals as given, else the normalized sum of the face normals.
NormalFields method_normals(const SurfelMesh& mesh, NormalKind need, py::handle face_normals,
                            py::handle vertex_normals) {
  if (need == NormalKind::None) return {};
  const NormalRequest request =
      given_normals_arg(face_normals, need == NormalKind::Vertex ? vertex_normals : py::handle(Py_None), mesh);
  py::gil_scoped_release release;
  return resolve_normals(mesh, need, request, nullptr, nullptr, "laplacian");
}

const char* normal_kind_name(NormalKind kind) {
  return kind == NormalKind::Face ? "face" : kind == NormalKind::Vertex ? "vertex" : "none";
}

}  // namespace

void bind_operators(py::module_& m) {
  m.def(
      "laplacian",
      [](py::handle V, py::handle F, const std::string& method, py::handle face_normals, py::handle vertex_normals,
         std::optional<double> h, const py::dict& params) {
        const auto disc = make_discretization(method);
        const SurfelMesh mesh = mesh_arg(V, F, h);
        const Config config = config_arg(params, method);
        const NormalKind need = disc->required_normals();
        NormalFields normals = method_normals(mesh, need, face_normals, vertex_normals);
        // Initialized from the call, not assigned: Eigen 3.4's SparseMatrix has no move assignment,
        // so assigning Operators would copy L and M (a third of the time at 750K faces).
        Operators ops = [&] {
          py::gil_scoped_release release;
          if (need == NormalKind::Vertex && !normals.has_vertex() && normals.has_face())
            normals.vertex = vertex_normals_from_face_normals(normals.face, mesh.faces, mesh.num_vertices());
          return disc->assemble(mesh, normals, config);
        }();
        py::list warnings;
        for (const auto& w : ops.warnings) warnings.append(w);
        const char* domain = ops.domain == Operators::Domain::Faces ? "faces" : "vertices";
        return py::make_tuple(sparse_out(std::move(ops.L)), sparse_out(std::move(ops.M)), domain, warnings);
      },
      py::arg("V"), py::arg("F"), py::arg("method"), py::arg("face_normals"), py::arg("vertex_normals"), py::arg("h"),
      py::arg("params"));
  m.def(
      "methods",
      [] {
        py::dict out;
        for (const auto& name : discretization_registry().names()) {
          const auto disc = make_discretization(name);
          py::list params;
          for (const auto& p : disc->parameters().info())
            params.append(py::make_tuple(p.name, p.default_value, p.description));
          out[py::str(name)] = py::make_tuple(normal_kind_name(disc->required_normals()), params);
        }
        return out;
      },
      "{name: (normals needed, [(parameter, default, description)])} of every registered discretization");
  // The C++ side of bench/bench_python.py: the registry's fem assembly alone, inputs converted
  // beforehand, in seconds (the operators are dropped).
  m.def(
      "_time_fem_assembly",
      [](py::handle V, py::handle F, py::handle face_normals) {
        const SurfelMesh mesh = mesh_arg(V, F);
        NormalFields normals;
        normals.face = points_arg(face_normals, "face_normals", mesh.num_faces());
        const auto disc = make_discretization("fem");
        py::gil_scoped_release release;
        const auto t0 = std::chrono::steady_clock::now();
        const Operators ops = disc->assemble(mesh, normals, Config());
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      },
      py::arg("V"), py::arg("F"), py::arg("face_normals"));
}

}  // namespace corrlap::python

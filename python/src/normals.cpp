// Normal fields and curvature: true_normals, ii_normals (from a shape or a volume), curvature; the
// normals through the library's resolve_normals, as every front end.
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <optional>

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
py::array_t<double> ii_normals(const VoxelGrid& grid, py::handle V, py::handle F, const IIParams& ii,
                               const std::string& at) {
  const bool vertices = at_vertices(at);
  const SurfelMesh given = mesh_arg(V, F);
  Eigen::MatrixX3d n;
  {
    py::gil_scoped_release release;
    const SurfelMesh mesh = extract_surface(grid);
    if (mesh.faces != given.faces || mesh.positions != given.positions)
      throw InputError("V, F: not the surface of these voxels (" + std::to_string(mesh.num_vertices()) +
                       " vertices and " + std::to_string(mesh.num_faces()) + " faces expected, " +
                       std::to_string(given.num_vertices()) + " and " + std::to_string(given.num_faces()) +
                       " given): pass the V, F that digitize returned for the same shape or volume and parameters");
    NormalRequest request;
    request.source = NormalSource::II;
    request.ii = ii;
    const NormalFields fields =
        resolve_normals(mesh, vertices ? NormalKind::Vertex : NormalKind::Face, request, nullptr, &grid, "ii_normals");
    n = vertices ? fields.vertex : fields.face;
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
        const SurfelMesh mesh = mesh_arg(V, F);
        NormalFields n;
        {
          py::gil_scoped_release release;
          // Vertex normals as --normals true gives them: the normalized sum of the face normals.
          NormalRequest request;
          request.source = NormalSource::True;
          n = resolve_normals(mesh, vertices ? NormalKind::Vertex : NormalKind::Face, request, &s, nullptr,
                              "true_normals");
        }
        return to_numpy(vertices ? n.vertex : n.face);
      },
      py::arg("shape"), py::arg("V"), py::arg("F"), py::arg("at"), py::arg("center"));
  m.def(
      "ii_normals_shape",
      [](const std::string& shape, py::handle V, py::handle F, double h, double bbox_min, double bbox_max, int offset,
         py::handle center, std::optional<double> k, std::optional<double> alpha, const std::string& at,
         std::optional<std::string> thin_parts) {
        return ii_normals(shape_voxels(shape, h, bbox_min, bbox_max, offset, center), V, F,
                          default_ii_params(/*implicit_shape=*/true, k, alpha, thin_parts_arg(thin_parts)), at);
      },
      py::arg("shape"), py::arg("V"), py::arg("F"), py::arg("h"), py::arg("bbox_min"), py::arg("bbox_max"),
      py::arg("offset"), py::arg("center"), py::arg("k"), py::arg("alpha"), py::arg("at"), py::arg("thin_parts"));
  m.def(
      "ii_normals_volume",
      [](py::handle volume, py::handle V, py::handle F, std::optional<double> h, double threshold,
         std::optional<double> k, std::optional<double> alpha, const std::string& at,
         std::optional<std::string> thin_parts) {
        return ii_normals(array_voxels(volume, h, threshold), V, F,
                          default_ii_params(/*implicit_shape=*/false, k, alpha, thin_parts_arg(thin_parts)), at);
      },
      py::arg("volume"), py::arg("V"), py::arg("F"), py::arg("h"), py::arg("threshold"), py::arg("k"), py::arg("alpha"),
      py::arg("at"), py::arg("thin_parts"));
  m.def(
      "curvature",
      [](py::handle V, py::handle F, py::object face_normals, py::object vertex_normals, std::optional<double> radius,
         const std::string& at, bool constant) {
        const bool vertices = at_vertices(at);
        const SurfelMesh mesh = mesh_arg(V, F);
        const NormalRequest request = given_normals_arg(face_normals, vertex_normals, mesh);
        const bool have_face = request.face_normals.rows() > 0;
        if (constant && !have_face) throw py::value_error("face_normals: constant=True needs face normals");
        if (!constant && !have_face && request.vertex_normals.rows() == 0)
          throw py::value_error("face_normals, vertex_normals: give one of them");
        CurvatureEstimates e;
        {
          py::gil_scoped_release release;
          // As `corrlap curvature --normals`: interpolated vertex normals, the normalized sum of the
          // face normals unless given; constant face normals on request.
          const NormalFields n = resolve_normals(mesh, constant ? NormalKind::Face : NormalKind::Vertex, request,
                                                 nullptr, nullptr, "curvature");
          const CorrectedCurvature cc =
              constant ? CorrectedCurvature::constant(mesh, n.face) : CorrectedCurvature::interpolated(mesh, n.vertex);
          // The default of `corrlap curvature --mesh`: a mesh given as it is, whose voxels (if any) are unknown.
          const double r = radius ? *radius
                                  : default_curvature_radius(regularization_size(mesh), mesh.grid_step(),
                                                             /*voxels_from_file=*/false);
          e = vertices ? cc.at_vertices(r) : cc.at_faces(r);
        }
        return py::make_tuple(to_numpy(e.H), to_numpy(e.G), to_numpy(e.k1), to_numpy(e.k2), to_numpy(e.d1),
                              to_numpy(e.d2));
      },
      py::arg("V"), py::arg("F"), py::arg("face_normals"), py::arg("vertex_normals"), py::arg("radius"), py::arg("at"),
      py::arg("constant"));
}

}  // namespace corrlap::python

#include "methods.hpp"

#include "registry.hpp"

namespace corrlap {

namespace {
NormalFields face_field(const Eigen::MatrixX3d& face_normals) {
  NormalFields n;
  n.face = face_normals;
  return n;
}
NormalFields vertex_field(const Eigen::MatrixX3d& vertex_normals) {
  NormalFields n;
  n.vertex = vertex_normals;
  return n;
}
}  // namespace

Operators assemble_operators(const std::string& method, const SurfelMesh& mesh, const NormalFields& normals,
                             const Config& options) {
  return make_discretization(method)->assemble(mesh, normals, options);
}

Operators corrected_fem(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Config& options) {
  return assemble_operators("fem", mesh, face_field(face_normals), options);
}

Operators interpolated(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals, const Config& options) {
  return assemble_operators("interpolated", mesh, vertex_field(vertex_normals), options);
}

Operators polydec(const SurfelMesh& mesh, const Config& options) {
  return assemble_operators("polydec", mesh, NormalFields{}, options);
}

Operators projected_polydec(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Config& options) {
  return assemble_operators("projected-polydec", mesh, face_field(face_normals), options);
}

Operators vrm(const SurfelMesh& mesh, const Config& options) {
  return assemble_operators("vrm", mesh, NormalFields{}, options);
}

Operators corrected_vrm(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals, const Config& options) {
  return assemble_operators("corrected-vrm", mesh, vertex_field(vertex_normals), options);
}

Operators heat_kernel(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Config& options) {
  return assemble_operators("heat-kernel", mesh, face_field(face_normals), options);
}

Operators cotan(const SurfelMesh& mesh, const Config& options) {
  return assemble_operators("cotan", mesh, NormalFields{}, options);
}

}  // namespace corrlap

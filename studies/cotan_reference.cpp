#include "cotan_reference.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/cotan.hpp>
#include <corrlap/surface/loop_subdivision.hpp>
#include <string>
#include <utility>
#include <vector>

namespace corrlap {
namespace {

// The study voxelizes the inside of the mesh and compares on the whole digital surface, which is
// closed: an open mesh has no inside, and its boundary would be compared with the cut of the
// voxels. Checked before the subdivision, whose vertex budget an open mesh can defeat.
void require_closed(const TriangleIndices& triangles) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(3 * std::size_t(triangles.rows()));
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles(f, k), b = triangles(f, (k + 1) % 3);
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  long long open = 0, nonmanifold = 0;
  std::pair<int, int> example{-1, -1};
  for (std::size_t i = 0, j = 0; i < edges.size(); i = j) {
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 2) continue;
    if (example.first < 0) example = edges[i];
    (j - i == 1 ? open : nonmanifold) += 1;
  }
  if (open == 0 && nonmanifold == 0) return;
  throw InputError("cotan study: the mesh is not closed: " + std::to_string(open) + " boundary edge(s), " +
                       std::to_string(nonmanifold) + " edge(s) with more than two triangles (e.g. the edge between " +
                       "vertices " + std::to_string(example.first) + " and " + std::to_string(example.second) +
                       ", numbered from 0); the study voxelizes the inside of the mesh and compares on its whole "
                       "surface, so it needs a closed (watertight) triangle mesh: close its holes first",
                   "mesh_file");
}

}  // namespace

CotanReference make_cotan_reference(const PolygonMesh& mesh, const std::vector<const TestFunction*>& functions,
                                    long long min_vertices) {
  if (mesh.positions.rows() == 0 || mesh.faces.empty()) throw InputError("cotan study: the mesh is empty");
  if (!mesh.positions.allFinite()) throw InputError("cotan study: a vertex position is not finite");
  CotanReference ref;
  ref.input_vertices = int(mesh.positions.rows());
  TriangleMesh t{mesh.positions, triangulate(mesh)};
  ref.input_triangles = int(t.triangles.rows());
  require_closed(t.triangles);
  const Eigen::Vector3d lo = t.positions.colwise().minCoeff(), hi = t.positions.colwise().maxCoeff();
  const double side = (hi - lo).maxCoeff();
  if (!(side > 0)) throw InputError("cotan study: the mesh has no extent");
  ref.center = 0.5 * (lo + hi);
  ref.scale = side / 2.0;
  t.positions = (t.positions.rowwise() - ref.center.transpose()) / ref.scale;
  ref.subdivision_steps = loop_refine(t, min_vertices);
  ref.positions = std::move(t.positions);
  ref.triangles = std::move(t.triangles);

  const Eigen::Index nv = ref.positions.rows();
  ref.normals.setZero(nv, 3);
  for (Eigen::Index f = 0; f < ref.triangles.rows(); ++f) {
    const Eigen::Vector3d a = ref.positions.row(ref.triangles(f, 0)), b = ref.positions.row(ref.triangles(f, 1)),
                          c = ref.positions.row(ref.triangles(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a).transpose();  // |n| = 2 area: area weights
    for (int k = 0; k < 3; ++k) ref.normals.row(ref.triangles(f, k)) += n;
  }
  for (Eigen::Index v = 0; v < nv; ++v) {
    const double len = ref.normals.row(v).norm();
    if (!(len > 0))
      throw InputError("cotan study: vertex " + std::to_string(v) +
                       " of the refined mesh has no normal (no triangle, or its triangles cancel)");
    ref.normals.row(v) /= len;
  }

  // Ground truth (paper §3.4): the cotan Laplacian M^-1 L f of each function on the refined mesh.
  ref.cotan = assemble_cotan(ref.positions, ref.triangles, CotanMass::Voronoi);
  const Operators& ops = ref.cotan;
  const Eigen::VectorXd mass = ops.M.diagonal();
  ref.f.resize(nv, Eigen::Index(functions.size()));
  for (std::size_t j = 0; j < functions.size(); ++j) {
    ref.functions.push_back(functions[j]);
    for (Eigen::Index v = 0; v < nv; ++v)
      ref.f(v, Eigen::Index(j)) = functions[j]->value(ref.positions.row(v).transpose());
  }
  ref.laplacian = (ops.L * ref.f).array().colwise() / mass.array();
  ref.locator = std::make_shared<const TriangleLocator>(ref.positions, ref.triangles);
  return ref;
}

Eigen::MatrixXd diffused_reference_laplacian(const CotanReference& ref, double dt) {
  if (dt == 0.0) return ref.laplacian;
  // M - dt L is SPD (M diagonal positive, L negative semi-definite): a simplicial LDLT suffices at
  // the reference's ~1e5 vertices.
  const Eigen::SparseMatrix<double> A = ref.cotan.M - dt * ref.cotan.L;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  if (solver.info() != Eigen::Success)
    throw NumericalError("cotan study: the diffused reference system M - dt L could not be factorized");
  return solver.solve(ref.cotan.L * ref.f);
}

ReferenceSamples sample_reference(const CotanReference& ref, const Eigen::MatrixXd& laplacian,
                                  const Eigen::MatrixX3d& points, const Eigen::Vector3d& shift,
                                  ReferenceValues values) {
  if (laplacian.rows() != ref.positions.rows() || laplacian.cols() != ref.f.cols())
    throw InputError("cotan study: the reference Laplacian has the wrong shape");
  const Eigen::MatrixX3d moved = points.rowwise() - shift.transpose();
  const std::vector<ClosestPoint> feet = closest_points(*ref.locator, moved);
  ReferenceSamples s;
  const Eigen::Index n = points.rows(), nf = ref.f.cols();
  s.f.resize(n, nf);
  s.laplacian.resize(n, nf);
  s.normals.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const ClosestPoint& p = feet[std::size_t(i)];
    s.max_distance = std::max(s.max_distance, p.distance);
    s.f.row(i).setZero();
    s.laplacian.row(i).setZero();
    Eigen::RowVector3d normal = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const int v = ref.triangles(p.triangle, k);
      s.f.row(i) += p.barycentric[k] * ref.f.row(v);
      s.laplacian.row(i) += p.barycentric[k] * laplacian.row(v);
      normal += p.barycentric[k] * ref.normals.row(v);
    }
    // Interpolated unit normals can only cancel across a fold sharper than 180 degrees.
    if (values == ReferenceValues::AtFoot)
      for (Eigen::Index j = 0; j < nf; ++j) s.f(i, j) = ref.functions[std::size_t(j)]->value(p.point);
    const double len = normal.norm();
    s.normals.row(i) = len > 0 ? Eigen::RowVector3d(normal / len) : ref.normals.row(ref.triangles(p.triangle, 0));
  }
  return s;
}

}  // namespace corrlap

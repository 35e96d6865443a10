#include "quad_assembly.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <vector>

namespace corrlap {

QuadCorners quad_corners(const SurfelMesh& mesh, int f) { return quad_corner_rows(mesh, mesh.positions, f); }

QuadCorners quad_corner_rows(const SurfelMesh& mesh, const Eigen::MatrixX3d& field, int f) {
  QuadCorners x;
  for (int k = 0; k < 4; ++k) x.row(k) = field.row(mesh.faces(f, k));
  return x;
}

const Eigen::Matrix4d& quad_difference() {
  static const Eigen::Matrix4d D = [] {
    Eigen::Matrix4d d = Eigen::Matrix4d::Zero();
    for (int i = 0; i < 4; ++i) {
      d(i, i) = -1.0;
      d(i, (i + 1) % 4) = 1.0;
    }
    return d;
  }();
  return D;
}

AssemblyPlan quad_vertex_plan(const SurfelMesh& mesh) {
  return AssemblyPlan(mesh.faces.data(), std::size_t(mesh.num_faces()), 4, mesh.num_vertices());
}

AssemblyPlan quad_corner_diagonal_plan(const SurfelMesh& mesh) {
  // faces is row-major #F x 4, so its data is the list of (face, corner) vertex ids in order.
  return AssemblyPlan(mesh.faces.data(), std::size_t(mesh.num_faces()) * 4, 1, mesh.num_vertices());
}

AssemblyPlan quad_edge_plan(const EdgeTopology& t) {
  return AssemblyPlan(t.face_edges.data(), std::size_t(t.face_edges.rows()), 4, t.num_edges(),
                      t.face_edge_signs.data());
}

Eigen::SparseMatrix<double> global_d0(const EdgeTopology& t, int num_vertices) {
  Eigen::SparseMatrix<double, Eigen::RowMajor> D(t.num_edges(), num_vertices);
  D.reserve(Eigen::VectorXi::Constant(t.num_edges(), 2));
  for (int e = 0; e < t.num_edges(); ++e) {
    D.insert(e, t.edges(e, 0)) = -1.0;
    D.insert(e, t.edges(e, 1)) = 1.0;
  }
  D.makeCompressed();
  return Eigen::SparseMatrix<double>(D);
}

Eigen::SparseMatrix<double> global_sharp(const EdgeTopology& t, const double* sharp) {
  const int F = int(t.face_edges.rows());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(std::size_t(F) * 12);
  for (int f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i)
      for (int c = 0; c < 3; ++c) {
        const double v = double(t.face_edge_signs(f, i)) * sharp[std::size_t(f) * 12 + std::size_t(i) * 3 + c];
        trip.emplace_back(3 * f + c, t.face_edges(f, i), v);
      }
  Eigen::SparseMatrix<double> U(3 * F, t.num_edges());
  U.setFromTriplets(trip.begin(), trip.end());
  return U;
}

Eigen::SparseMatrix<double> global_flat(const EdgeTopology& t, const double* flat) {
  const int F = int(t.face_edges.rows());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(std::size_t(F) * 12);
  for (int f = 0; f < F; ++f)
    for (int i = 0; i < 4; ++i) {
      const int e = t.face_edges(f, i);
      const double w = double(t.face_edge_signs(f, i)) / double(t.faces_per_edge[std::size_t(e)]);
      for (int c = 0; c < 3; ++c)
        trip.emplace_back(e, 3 * f + c, w * flat[std::size_t(f) * 12 + std::size_t(c) * 4 + i]);
    }
  Eigen::SparseMatrix<double> V(t.num_edges(), 3 * F);
  V.setFromTriplets(trip.begin(), trip.end());
  return V;
}

Eigen::SparseMatrix<double> row_sum_lumped(const Eigen::SparseMatrix<double>& A) {
  Eigen::VectorXd s = Eigen::VectorXd::Zero(A.rows());
  for (int c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) s[it.row()] += it.value();
  Eigen::SparseMatrix<double> D(A.rows(), A.cols());
  D.reserve(Eigen::VectorXi::Constant(A.cols(), 1));
  for (Eigen::Index i = 0; i < A.rows(); ++i) D.insert(i, i) = s[i];
  D.makeCompressed();
  return D;
}

void validate_mesh(const SurfelMesh& mesh, const char* what) {
  // The checks of SurfelMesh::validate as a parallel scan; only a mesh that fails one goes
  // through SurfelMesh::validate itself, which then reports the first failure with its message.
  // (The serial scan was a noticeable share of the fastest assemblies.)
  const int nv = mesh.num_vertices();
  const int* faces = mesh.faces.data();  // row-major #F x 4
  const Eigen::Index F = mesh.faces.rows(), P = mesh.positions.rows();
  const bool ok = tbb::parallel_reduce(
      tbb::blocked_range<Eigen::Index>(0, std::max(F, P), 1 << 14), true,
      [&](const tbb::blocked_range<Eigen::Index>& r, bool good) {
        for (Eigen::Index i = r.begin(); good && i != r.end(); ++i) {
          if (i < F) {
            const int* q = faces + 4 * i;
            for (int j = 0; j < 4; ++j) {
              good = good && q[j] >= 0 && q[j] < nv;
              for (int k = 0; k < j; ++k) good = good && q[k] != q[j];
            }
          }
          if (i < P) good = good && mesh.positions.row(i).allFinite();
        }
        return good;
      },
      [](bool a, bool b) { return a && b; });
  if (!ok || (!mesh.surfels.empty() && mesh.surfels.size() != std::size_t(F))) mesh.validate(what);
}

void check_quad_mesh(const SurfelMesh& mesh, const std::string& method) {
  if (mesh.num_faces() == 0 || mesh.num_vertices() == 0) throw InputError(method + ": the mesh has no face");
  validate_mesh(mesh, (method + ": mesh").c_str());
}

Parameter extras_parameter() {
  return Parameter::boolean("extras", false, "also build D0, sharp, flat, M1 and M_lumped", "§2.3, §3.6");
}

}  // namespace corrlap

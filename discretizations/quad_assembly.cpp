#include "quad_assembly.hpp"

#include <algorithm>
#include <cstring>
#include <mutex>
#include <vector>

#include <corrlap/core/error.hpp>

#include <corrlap/discretizations/assembly/detail/quad_row_gather.hpp>

#include <tbb/parallel_reduce.h>

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
      for (int c = 0; c < 3; ++c) trip.emplace_back(e, 3 * f + c, w * flat[std::size_t(f) * 12 + std::size_t(c) * 4 + i]);
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

namespace detail {

namespace {
std::shared_ptr<const QuadVertexPattern> build_quad_vertex_pattern(const SurfelMesh& mesh) {
  auto p = std::make_shared<QuadVertexPattern>();
  const int V = mesh.num_vertices(), F = mesh.num_faces();
  const int* faces = mesh.faces.data();
  p->num_vertices = V;
  // Read by every assembly on this connectivity: huge pages from the start.
  assign_on_huge_pages(p->faces, faces, faces + std::size_t(F) * 4);
  p->vc = vertex_corners(mesh);
  const VertexCorners& vc = p->vc;
  const std::size_t cap = std::size_t(4 * vc.max_degree + 1);
  if (cap > 65535) return nullptr;
  tbb::enumerable_thread_specific<ColumnScratch> scratch([&] { return ColumnScratch(V, cap); });
  assign_on_huge_pages(p->outer, std::size_t(V) + 1);
  int* outer = p->outer.data();
  count_column_rows(faces, vc, V, scratch, outer);  // pass 1: distinct rows per column
  assign_on_huge_pages(p->inner, std::size_t(outer[V]));
  assign_on_huge_pages(p->slot, std::size_t(F) * 16);  // 4 incidences per face, 4 slots each
  // Pass 2: sorted rows and the slot of every (incidence, corner).
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    ColumnScratch& sc = scratch.local();
    const int* pos = sc.pos.data();
    for (int v = r.begin(); v != r.end(); ++v) {
      const int n = column_rows(faces, vc, V, v, sc);
      std::copy_n(sc.list.data(), n, p->inner.data() + outer[v]);
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
        for (int j = 0; j < 4; ++j) p->slot[std::size_t(a) * 4 + std::size_t(j)] = std::uint16_t(pos[f[j]]);
      }
    }
  });
  return p;
}

std::mutex scratch_mutex;
std::vector<std::pair<std::unique_ptr<double[]>, std::size_t>> scratch_pool;

std::mutex cache_mutex;
std::shared_ptr<const QuadVertexPattern> cached_pattern;
}  // namespace

std::shared_ptr<const QuadVertexPattern> quad_vertex_pattern(const SurfelMesh& mesh) {
  const std::size_t n = std::size_t(mesh.num_faces()) * 4;
  std::shared_ptr<const QuadVertexPattern> c;
  {
    std::lock_guard<std::mutex> lock(cache_mutex);
    c = cached_pattern;
  }
  // Exact comparison of the connectivity (a few ms at most, far cheaper than rebuilding), by
  // chunks in parallel.
  if (c && c->num_vertices == mesh.num_vertices() && c->faces.size() == n &&
      tbb::parallel_reduce(
          tbb::blocked_range<std::size_t>(0, n, 1 << 18), true,
          [&](const tbb::blocked_range<std::size_t>& r, bool same) {
            return same && std::memcmp(c->faces.data() + r.begin(), mesh.faces.data() + r.begin(),
                                       (r.end() - r.begin()) * sizeof(int)) == 0;
          },
          [](bool a, bool b) { return a && b; }))
    return c;
  c = build_quad_vertex_pattern(mesh);
  if (c) {
    std::lock_guard<std::mutex> lock(cache_mutex);
    cached_pattern = c;
  }
  return c;
}

ReusedScratch::ReusedScratch(std::size_t n) {
  {
    std::lock_guard<std::mutex> lock(scratch_mutex);
    if (!scratch_pool.empty()) {
      buf_ = std::move(scratch_pool.back().first);
      capacity_ = scratch_pool.back().second;
      scratch_pool.pop_back();
    }
  }
  if (capacity_ < n) {
    buf_.reset(new double[n]);
    capacity_ = n;
    advise_huge_pages(buf_.get(), n * sizeof(double));
  }
}

ReusedScratch::~ReusedScratch() {
  std::lock_guard<std::mutex> lock(scratch_mutex);
  if (scratch_pool.size() < 2) scratch_pool.emplace_back(std::move(buf_), capacity_);
}

void clear_quad_vertex_pattern_cache() {
  {
    std::lock_guard<std::mutex> lock(scratch_mutex);
    scratch_pool.clear();
  }
  std::lock_guard<std::mutex> lock(cache_mutex);
  cached_pattern.reset();
}

}  // namespace detail

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

ParameterInfo extras_parameter() {
  return {"extras", "false", "also build D0, sharp, flat, M1 and M_lumped (spec §2.3, §3.6)"};
}

}  // namespace corrlap

#include "quad_pattern.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/quad_assembly.hpp>
#include <cstring>

#include "detail/quad_pattern_access.hpp"

namespace corrlap {

namespace {
void build_vertex_pattern(const SurfelMesh& mesh, detail::QuadVertexPattern& p) {
  const int V = mesh.num_vertices(), F = mesh.num_faces();
  const int* faces = mesh.faces.data();
  p.num_vertices = V;
  p.vc = detail::vertex_corners(mesh);
  const detail::VertexCorners& vc = p.vc;
  const std::size_t cap = std::size_t(4 * vc.max_degree + 1);
  if (cap > 65535) return;  // uint16 slots: the direct gather over vc
  tbb::enumerable_thread_specific<detail::ColumnScratch> scratch([&] { return detail::ColumnScratch(V, cap); });
  // Read by every assembly on this connectivity: huge pages from the start.
  assign_on_huge_pages(p.outer, std::size_t(V) + 1);
  int* outer = p.outer.data();
  detail::count_column_rows(faces, vc, V, scratch, outer);  // pass 1: distinct rows per column
  assign_on_huge_pages(p.inner, std::size_t(outer[V]));
  assign_on_huge_pages(p.slot, std::size_t(F) * 16);  // 4 incidences per face, 4 slots each
  // Pass 2: sorted rows and the slot of every (incidence, corner).
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    detail::ColumnScratch& sc = scratch.local();
    const int* pos = sc.pos.data();
    for (int v = r.begin(); v != r.end(); ++v) {
      const int n = detail::column_rows(faces, vc, V, v, sc);
      std::copy_n(sc.list.data(), n, p.inner.data() + outer[v]);
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
        for (int j = 0; j < 4; ++j) p.slot[std::size_t(a) * 4 + std::size_t(j)] = std::uint16_t(pos[f[j]]);
      }
    }
  });
  p.has_slots = true;
}
}  // namespace

QuadPattern QuadPattern::build(const SurfelMesh& mesh) {
  check_quad_mesh(mesh, "QuadPattern::build");
  auto impl = std::make_shared<Impl>();
  const int* faces = mesh.faces.data();
  assign_on_huge_pages(impl->faces, faces, faces + std::size_t(mesh.num_faces()) * 4);
  build_vertex_pattern(mesh, impl->vertex);
  return QuadPattern(std::move(impl));
}

int QuadPattern::num_vertices() const { return impl_->vertex.num_vertices; }
int QuadPattern::num_faces() const { return int(impl_->faces.size() / 4); }

bool QuadPattern::matches(const SurfelMesh& mesh) const {
  const std::size_t n = std::size_t(mesh.num_faces()) * 4;
  const int* mine = impl_->faces.data();
  const int* theirs = mesh.faces.data();
  // Exact comparison of the whole connectivity, by chunks in parallel (a few ms at h = 0.005).
  return mesh.num_vertices() == num_vertices() && impl_->faces.size() == n &&
         tbb::parallel_reduce(
             tbb::blocked_range<std::size_t>(0, n, 1 << 18), true,
             [&](const tbb::blocked_range<std::size_t>& r, bool same) {
               return same &&
                      std::memcmp(mine + r.begin(), theirs + r.begin(), (r.end() - r.begin()) * sizeof(int)) == 0;
             },
             [](bool a, bool b) { return a && b; });
}

void QuadPattern::check(const SurfelMesh& mesh, const std::string& who) const {
  if (matches(mesh)) return;
  throw InputError(
      who + ": the QuadPattern was built for another connectivity (" + std::to_string(num_vertices()) + " vertices, " +
      std::to_string(num_faces()) + " faces; this mesh has " + std::to_string(mesh.num_vertices()) + " vertices, " +
      std::to_string(mesh.num_faces()) + " faces" +
      (mesh.num_faces() == num_faces() && mesh.num_vertices() == num_vertices() ? ", other face ids" : "") +
      "): build one with QuadPattern::build(mesh)");
}

std::size_t QuadPattern::memory_bytes() const {
  auto b = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  const detail::QuadVertexPattern& p = impl_->vertex;
  std::size_t s = b(impl_->faces) + b(p.vc.start) + b(p.vc.corner) + b(p.outer) + b(p.inner) + b(p.slot);
  {
    std::lock_guard<std::mutex> lock(impl_->scratch_mutex);
    for (const auto& e : impl_->scratch_pool) s += e.second * sizeof(double);
  }
  if (impl_->projection_ready.load(std::memory_order_acquire)) s += detail::memory_bytes(*impl_->projection);
  return s;
}

namespace detail {

VertexGather::VertexGather(const SurfelMesh& mesh, const QuadPattern* pattern, const std::string& who) {
  if (pattern) {
    pattern->check(mesh, who);
    const QuadVertexPattern& p = QuadPatternAccess::impl(*pattern).vertex;
    vc_ = &p.vc;
    gather_ = p.has_slots ? &p : nullptr;
  } else {
    own_ = vertex_corners(mesh);
    vc_ = &own_;
  }
}

const ProjectionPattern& projection_pattern(const QuadPattern& p) {
  QuadPattern::Impl& impl = QuadPatternAccess::impl(p);
  std::call_once(impl.projection_once, [&] {
    impl.projection = build_projection_pattern(impl.faces.data(), int(impl.faces.size() / 4), impl.vertex.vc);
    impl.projection_ready.store(true, std::memory_order_release);
  });
  return *impl.projection;
}

PatternScratch::PatternScratch(const QuadPattern* pattern, std::size_t n) {
  if (pattern) {
    owner_ = &QuadPatternAccess::impl(*pattern);
    std::lock_guard<std::mutex> lock(owner_->scratch_mutex);
    if (!owner_->scratch_pool.empty()) {
      buf_ = std::move(owner_->scratch_pool.back().first);
      capacity_ = owner_->scratch_pool.back().second;
      owner_->scratch_pool.pop_back();
    }
  }
  if (capacity_ < n) {
    buf_ = fresh_buffer(n);
    capacity_ = n;
  }
}

PatternScratch::~PatternScratch() {
  if (!owner_) return;
  std::lock_guard<std::mutex> lock(owner_->scratch_mutex);
  if (owner_->scratch_pool.size() < 2) owner_->scratch_pool.emplace_back(std::move(buf_), capacity_);
}

}  // namespace detail
}  // namespace corrlap

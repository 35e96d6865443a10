#pragma once
// Internals of QuadPattern (quad_pattern.hpp) for the method files: the vertex pattern, the lazily
// built projection pattern, and per-pattern scratch reuse. Internal header.
#include <atomic>
#include <corrlap/discretizations/assembly/quad_pattern.hpp>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "projection_pattern.hpp"
#include "quad_row_gather.hpp"

namespace corrlap {

struct QuadPattern::Impl {
  std::vector<int> faces;  // the connectivity it was built from (validity check, not a cache key)
  detail::QuadVertexPattern vertex;
  // Interpolated global projection (docs/math.md §3.6a), built on first use.
  std::once_flag projection_once;
  std::unique_ptr<detail::ProjectionPattern> projection;
  std::atomic<bool> projection_ready{false};  // for memory_bytes, which must not build it
  // Per-face scratch kept between assemblies on this mesh (PatternScratch): a fresh multi-MiB
  // buffer costs more in first-touch page faults than the kernel that fills it.
  std::mutex scratch_mutex;
  std::vector<std::pair<std::unique_ptr<double[]>, std::size_t>> scratch_pool;
};

namespace detail {

struct QuadPatternAccess {
  static QuadPattern::Impl& impl(const QuadPattern& p) { return *p.impl_; }
};

/// The vertex incidence and, when possible, the gather pattern for one assembly: taken from
/// `pattern` (checked against the mesh: InputError naming `who` otherwise) or, without one, the
/// incidence alone computed from the mesh (the direct gather, no pattern build).
class VertexGather {
 public:
  VertexGather(const SurfelMesh& mesh, const QuadPattern* pattern, const std::string& who);
  /// nullptr: use the direct gather over vc().
  const QuadVertexPattern* pattern() const { return gather_; }
  const VertexCorners& vc() const { return *vc_; }

 private:
  VertexCorners own_;
  const VertexCorners* vc_ = nullptr;
  const QuadVertexPattern* gather_ = nullptr;
};

/// The interpolated projection pattern held by `p`, built on first use (thread-safe).
const ProjectionPattern& projection_pattern(const QuadPattern& p);

/// n uninitialized doubles: borrowed from the pattern's pool when a pattern is given (at most two
/// buffers are kept, so concurrent assemblies on one pattern simply allocate), else a fresh
/// buffer on huge pages. Returned to the pool on destruction.
class PatternScratch {
 public:
  PatternScratch(const QuadPattern* pattern, std::size_t n);
  ~PatternScratch();
  PatternScratch(const PatternScratch&) = delete;
  PatternScratch& operator=(const PatternScratch&) = delete;
  double* data() { return buf_.get(); }
  const double* data() const { return buf_.get(); }
  double& operator[](std::size_t i) { return buf_[i]; }
  const double& operator[](std::size_t i) const { return buf_[i]; }

 private:
  QuadPattern::Impl* owner_ = nullptr;
  std::unique_ptr<double[]> buf_;
  std::size_t capacity_ = 0;
};

}  // namespace detail
}  // namespace corrlap

#pragma once
// The symbolic part of the vertex assembly of a quad mesh, built once from the connectivity and
// reused by every numeric assembly on it (the model of Eigen's analyzePattern and CHOLMOD's
// analyze): the vertex -> corner incidence, the column structure of the #V x #V vertex matrices
// and the slot of every face corner in its column (docs/math.md §0 assembly A[v_i, v_j] += A_f[i, j]) and,
// built on first use, the edge/2-ring structure of the interpolated global projection (docs/math.md §3.6a).
//
//   const QuadPattern pattern = QuadPattern::build(mesh);
//   for (...) method->assemble_into(mesh, normals, params, pattern, ops);
//
// The caller owns the pattern and its memory; nothing is cached process-wide. Copies are cheap and
// share one immutable state (the lazily built parts are built once, thread-safely), so one pattern
// may serve concurrent assemblies. Results through a pattern are bitwise those of the one-shot
// assemble() without one.
#include <corrlap/core/surfel_mesh.hpp>
#include <cstddef>
#include <memory>
#include <string>

namespace corrlap {

namespace detail {
struct QuadPatternAccess;
}

class QuadPattern {
 public:
  /// Builds the pattern of `mesh` (in parallel). Throws InputError for an empty or invalid mesh.
  static QuadPattern build(const SurfelMesh& mesh);

  int num_vertices() const;
  int num_faces() const;
  /// True when `mesh` has exactly the connectivity the pattern was built from (same vertex count,
  /// same face array; positions may differ).
  bool matches(const SurfelMesh& mesh) const;
  /// Throws InputError naming `who` when matches(mesh) is false.
  void check(const SurfelMesh& mesh, const std::string& who) const;
  /// Bytes held by the pattern (including the lazily built parts built so far).
  std::size_t memory_bytes() const;

  struct Impl;

 private:
  explicit QuadPattern(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<Impl> impl_;  // never null; shared by copies
  friend struct detail::QuadPatternAccess;
};

}  // namespace corrlap

#pragma once
// Parallel assembly of per-element local matrices into a sparse matrix whose pattern is
// computed once. Deterministic: every matrix entry is a sum of its contributions in a fixed
// order (ascending element, then local index), so the result is bitwise identical for any
// thread count. No lock and no atomic in the hot loop.
#include <Eigen/Sparse>
#include <cstdint>
#include <functional>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace corrlap {

/// Assembly plan for elements with k vertex ids each, into an n x n matrix (vertex-based, docs/math.md §0:
/// A[v_i, v_j] += A_f[i, j]); with signs, edge-based: A[e_i, e_j] += s_i s_j A_f[i, j].
class AssemblyPlan {
 public:
  AssemblyPlan() = default;
  /// element_ids: num_elements x k ids (row-major) in [0, n). signs: optional, num_elements x k of +-1.
  AssemblyPlan(const int* element_ids, std::size_t num_elements, int k, int n, const std::int8_t* signs = nullptr);

  int local_size() const { return k_; }
  std::size_t num_elements() const { return num_elements_; }
  int size() const { return n_; }
  /// Pattern (values zero), compressed column-major.
  const Eigen::SparseMatrix<double>& pattern() const { return pattern_; }

  /// Sums the local matrices (num_elements * k * k values, element-major, each row-major k x k).
  Eigen::SparseMatrix<double> gather(const double* locals) const;

 private:
  int k_ = 0, n_ = 0;
  std::size_t num_elements_ = 0;
  Eigen::SparseMatrix<double> pattern_;
  // Allocator that leaves elements uninitialized: every element is written in a parallel loop,
  // where the first-touch page faults are then spread over the threads (a zero fill would be a
  // serial pass over memory that is overwritten anyway).
  template <class T>
  struct UninitAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
      using other = UninitAllocator<U>;
    };
    UninitAllocator() = default;
    template <class U>
    UninitAllocator(const UninitAllocator<U>&) noexcept {}
    template <class U>
    void construct(U* p) noexcept {
      ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  };
  std::vector<std::int64_t, UninitAllocator<std::int64_t>> start_;          // per stored entry: range in contributions_
  std::vector<std::int64_t, UninitAllocator<std::int64_t>> contributions_;  // (local entry index + 1) * sign
};

/// Fills local matrices for elements [begin, end) into `locals` (already offset to element begin).
using LocalKernel = std::function<void(std::size_t begin, std::size_t end, double* locals)>;

/// Runs the kernel over all elements in parallel (TBB), then gathers. Deterministic.
Eigen::SparseMatrix<double> assemble(const AssemblyPlan& plan, const LocalKernel& kernel);

}  // namespace corrlap

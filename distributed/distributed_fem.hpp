#pragma once
// The corrected FEM (docs/math.md §4, "fem", consistent mass) assembled on a DistributedSurface:
// each rank computes the local 4x4 matrices of its own faces and hands them to PETSc, which sums
// them into MPIAIJ matrices over MPI_COMM_WORLD (entries of rows owned elsewhere are sent there).
//
// L  #V by #V stiffness, symmetric NEGATIVE semi-definite (L 1 = 0, docs/math.md §0);
// M  #V by #V consistent mass (docs/math.md §4.4);
// rows and columns in the rank-major order of DistributedSurface::rows. An entry is the sum of the
// serial corrected_fem's face terms, bit for bit the same terms, added in another order.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "distributed_surface.hpp"

namespace corrlap {

class DistributedFem {
 public:
  /// Collective. `face_normals`: #Fl by 3 unit normals of the rank's faces (surface.mesh), e.g.
  /// true_face_normals(shape, surface.mesh). Normals with u . n_triv <= 0 on some face (where the
  /// serial method clamps, docs/discretizations.md) are refused with an InputError on every rank.
  DistributedFem(const DistributedSurface& surface, const Eigen::MatrixX3d& face_normals);
  ~DistributedFem();
  DistributedFem(const DistributedFem&) = delete;
  DistributedFem& operator=(const DistributedFem&) = delete;

  struct Entry {
    std::int64_t row = 0, column = 0;
    double value = 0.0;
  };
  enum class Which { L, M };
  /// The stored entries of the rows this rank owns (rank-major rows and columns).
  std::vector<Entry> owned_entries(Which which) const;

  struct Impl;
  /// The PETSc matrices (detail/petsc_matrices.hpp), for the distributed solvers.
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace corrlap

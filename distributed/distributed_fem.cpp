#include "distributed_fem.hpp"

#include <mpi.h>

#include <cmath>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/corrected_fem.hpp>
#include <corrlap/discretizations/quad_assembly.hpp>
#include <limits>

#include "detail/petsc_matrices.hpp"

namespace corrlap {

namespace {

using detail::petsc_check;

}  // namespace

void detail::coo_matrix(const DistributedSurface& s, const std::vector<PetscInt>& i, const std::vector<PetscInt>& j,
                        const std::vector<PetscScalar>& values, detail::PetscMatOwner& A) {
  petsc_check(MatCreate(PETSC_COMM_WORLD, A.out()), "MatCreate");
  petsc_check(MatSetSizes(A, s.num_owned, s.num_owned, PetscInt(s.num_vertices), PetscInt(s.num_vertices)),
              "MatSetSizes");
  petsc_check(MatSetType(A, MATAIJ), "MatSetType");
  // PETSc may reorder the index arrays it is given: copies.
  std::vector<PetscInt> rows = i, columns = j;
  petsc_check(MatSetPreallocationCOO(A, PetscCount(rows.size()), rows.data(), columns.data()),
              "MatSetPreallocationCOO");
  petsc_check(MatSetValuesCOO(A, values.data(), INSERT_VALUES), "MatSetValuesCOO");
  petsc_check(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  petsc_check(MatSetOption(A, MAT_SYMMETRY_ETERNAL, PETSC_TRUE), "MatSetOption");
}

DistributedFem::DistributedFem(const DistributedSurface& s, const Eigen::MatrixX3d& u)
    : impl_(std::make_unique<Impl>()) {
  ensure_petsc_runtime();
  const SurfelMesh& mesh = s.mesh;
  const int F = mesh.num_faces();
  if (u.rows() != F) throw InputError("distributed fem: one face normal per local face is needed");
  if (s.num_vertices > std::numeric_limits<PetscInt>::max() / 2)
    throw InputError("distributed fem: " + std::to_string(s.num_vertices) +
                     " vertices exceed this PETSc build's 32-bit indices");
  // The serial method repairs normals with u . n_triv <= 0 (orientation=clamp) only when some face
  // has one; that whole-surface decision is not made here yet.
  std::int64_t inconsistent = 0;
  for (int f = 0; f < F; ++f)
    if (!(u.row(f).dot(mesh.surfels[std::size_t(f)].trivial_normal().transpose()) > 0.0)) ++inconsistent;
  MPI_Allreduce(MPI_IN_PLACE, &inconsistent, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (inconsistent > 0)
    throw InputError("distributed fem: " + std::to_string(inconsistent) +
                     " faces whose normal has u . n_triv <= 0: the serial orientation policy is not distributed yet");

  // docs/math.md §4.2-§4.4 per face, by the serial method's own local matrices.
  const std::size_t count = std::size_t(F) * 16;
  std::vector<PetscInt> i(count), j(count);
  std::vector<PetscScalar> l(count), m(count);
  for (int f = 0; f < F; ++f) {
    const FemLocalFrame frame = corrected_fem_local_frame(quad_corners(mesh, f), u.row(f).transpose());
    const Eigen::Matrix4d K = corrected_fem_local_stiffness(frame.u_local);
    const Eigen::Matrix4d Mf = corrected_fem_local_mass(frame.area, frame.u_local.z());
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const std::size_t e = std::size_t(f) * 16 + std::size_t(4 * a + b);
        i[e] = PetscInt(s.rows[std::size_t(mesh.faces(f, a))]);
        j[e] = PetscInt(s.rows[std::size_t(mesh.faces(f, b))]);
        l[e] = -K(a, b);  // L_f = -K_f: L negative semi-definite
        m[e] = Mf(a, b);
      }
  }
  detail::coo_matrix(s, i, j, l, impl_->L);
  detail::coo_matrix(s, i, j, m, impl_->M);
}

DistributedFem::~DistributedFem() = default;

std::vector<DistributedFem::Entry> DistributedFem::owned_entries(Which which) const {
  Mat A = which == Which::L ? impl_->L : impl_->M;
  PetscInt begin = 0, end = 0;
  petsc_check(MatGetOwnershipRange(A, &begin, &end), "MatGetOwnershipRange");
  std::vector<Entry> entries;
  for (PetscInt r = begin; r < end; ++r) {
    PetscInt n = 0;
    const PetscInt* columns = nullptr;
    const PetscScalar* values = nullptr;
    petsc_check(MatGetRow(A, r, &n, &columns, &values), "MatGetRow");
    for (PetscInt k = 0; k < n; ++k) entries.push_back({r, columns[k], values[k]});
    petsc_check(MatRestoreRow(A, r, &n, &columns, &values), "MatRestoreRow");
  }
  return entries;
}

}  // namespace corrlap

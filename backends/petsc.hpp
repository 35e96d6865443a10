#pragma once
// PETSc and SLEPc behind the LinearSolver and EigenSolver contracts ("petsc", "slepc"), built only
// with -DCORRLAP_WITH_PETSC=ON (docs/backends.md, "PETSc and SLEPc under MPI").
//
// Every rank of MPI_COMM_WORLD calls the same methods with the same (whole, serial) matrices; each
// rank hands PETSc the triplets of its contiguous block of rows (COO assembly into an MPIAIJ
// matrix), PETSc solves in parallel, and every rank gets the whole solution back. The distributed
// front end (distributed/, docs/distributed.md), where no rank holds the whole surface, builds its
// own PETSc matrices and hands them to the same solvers through their *_distributed entry points
// (a handle of backends/detail/petsc_objects.hpp), so both front ends share one KSP and one EPS
// set-up.
// Run without mpirun, the process is an MPI singleton and everything happens on one rank.
//
// PETSc and SLEPc are initialized on first use (SlepcInitialize, which calls MPI_Init) and
// finalized once at exit. No PETSc header leaks from here (pimpl).
#include <corrlap/core/linear_solver.hpp>
#include <memory>

namespace corrlap {

namespace detail {
struct PetscDistributedMatrix;  // backends/detail/petsc_objects.hpp (PETSc's Mat)
}

/// Starts PETSc and SLEPc (and MPI) if they are not running yet; they are finalized at exit. For
/// code that calls PETSc itself (distributed/) before any solver exists.
void ensure_petsc_runtime();

/// For code that calls PETSc itself (distributed/): throws SolverError naming `call` when `code`
/// (a PetscErrorCode) is not 0, with PETSc's own message, as the backends report their failures
/// (OutOfMemory for PETSC_ERR_MEM).
void check_petsc_call(int code, const char* call);

/// "petsc": a KSP with named options (ksp_type, pc_type = cholesky (MUMPS) | gamg | hypre | jacobi |
/// none, rtol, max_it) and a pass-through of any other ksp_* / pc_* / mat_* key as the PETSc
/// option -ksp_* / -pc_* / -mat_*. A system whose rows sum to zero (A 1 = 0, e.g. -L) gets the
/// constant null space, and the solution with zero mean is returned. Divergence throws SolverError
/// naming PETSc's reason.
class PetscLinearSolver : public LinearSolver {
 public:
  PetscLinearSolver();
  ~PetscLinearSolver() override;

  std::string name() const override { return "petsc"; }
  std::vector<ParameterInfo> options() const override;
  void configure(const Config& options) override;
  void analyze(const Eigen::SparseMatrix<double>& A) override;
  void factorize(const Eigen::SparseMatrix<double>& A) override;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) override;
  const SolverReport& info() const override;

  /// True when the last factorize() found A 1 = 0 and set the constant null space.
  bool singular() const;

  /// factorize() for a matrix already spread over the ranks (the distributed front end): the same
  /// options, null space, MUMPS workspace retry, reports and failures, without analyze(). The
  /// solver keeps a reference to A until the next factorize. Collective.
  void factorize_distributed(const detail::PetscDistributedMatrix& A);
  /// solve() after factorize_distributed(): B and the result hold this rank's rows only (its row
  /// block of A, in A's order), no rank gathers the whole solution. Collective.
  Eigen::MatrixXd solve_distributed(const Eigen::MatrixXd& B);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// "slepc": the k smallest mu = -lambda of L u = lambda M u (the convention of the other eigen
/// solvers: ascending, M-orthonormal vectors), as the generalized Hermitian problem
/// K u = mu M u with K = -L (EPS_GHEP). method = shift-invert (default): Krylov-Schur on
/// (K - sigma M)^{-1} M with the target sigma just below 0 (K is singular), MUMPS's Cholesky in the
/// spectral transform; method = lobpcg: LOBPCG preconditioned by GAMG or hypre on K - sigma M, for
/// sizes where a factorization does not fit.
class SlepcEigenSolver : public EigenSolver {
 public:
  SlepcEigenSolver();
  ~SlepcEigenSolver() override;

  std::string name() const override { return "slepc"; }
  std::vector<ParameterInfo> options() const override;
  void configure(const Config& options) override;
  EigenResult solve(const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, int k) override;
  /// solve() for L and M already spread over the ranks (the distributed front end), with the same
  /// EPS set-up. Every rank gets the values; `vectors` holds this rank's rows only (its row block
  /// of L, M-orthonormal over all ranks). Collective.
  EigenResult solve_distributed(const detail::PetscDistributedMatrix& L, const detail::PetscDistributedMatrix& M,
                                int k);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace corrlap

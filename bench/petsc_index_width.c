/* PETSc's index width, measured: the memory and time of a matrix with a quad surface's rows (9
   entries: a periodic grid's 9-point stencil, shifted to be positive definite), assembled through
   COO as backends/petsc.cpp does, then solved by whatever -ksp_type / -pc_type say. Built against
   Debian's 32-bit (libpetsc-real-dev) and 64-bit (libpetsc64-real3.18-dev) PETSc, it gives the
   numbers behind docs/scaling.md "Index widths" (bench/RESULTS.md, "PETSc index width"):

     for w in "" 64; do
       mpicc -O2 -o petsc_index_width$w bench/petsc_index_width.c \
         $(PKG_CONFIG_PATH=/usr/lib/petsc$w/lib/pkgconfig pkg-config --cflags --libs PETSc) \
         -Wl,-rpath,/usr/lib/petsc$w/lib
     done
     ./petsc_index_width -side 1000 -ksp_type cg -pc_type gamg -ksp_rtol 1e-10

   Memory is the change in resident size (PetscMemoryGetCurrentUsage) around the assembly and
   around the solver's setup and solve: PETSc's own malloc accounting is off in release builds. */
#include <petscksp.h>

int main(int argc, char** argv) {
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscInt side = 1000;
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-side", &side, NULL));
  const PetscInt n = side * side;

  /* This rank's rows, as PETSC_DECIDE splits them. */
  PetscInt local = PETSC_DECIDE, global = n, end = 0;
  PetscCall(PetscSplitOwnership(PETSC_COMM_WORLD, &local, &global));
  PetscCallMPI(MPI_Scan(&local, &end, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  const PetscInt begin = end - local;

  const PetscCount count = 9 * (PetscCount)local;
  PetscInt *rows, *cols;
  PetscScalar* values;
  PetscCall(PetscMalloc3(count, &rows, count, &cols, count, &values));
  PetscCount k = 0;
  for (PetscInt r = begin; r < end; ++r) {
    const PetscInt x = r % side, y = r / side;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx, ++k) {
        rows[k] = r;
        cols[k] = ((y + dy + side) % side) * side + (x + dx + side) % side;
        values[k] = (dx == 0 && dy == 0) ? 8.0 + 1e-3 : -1.0;
      }
  }

  Mat A;
  PetscCall(MatCreate(PETSC_COMM_WORLD, &A));
  PetscCall(MatSetSizes(A, local, local, n, n));
  PetscCall(MatSetType(A, MATAIJ));
  PetscLogDouble before, assembled, solved, t0, t1, t2, t3;
  PetscCall(PetscMemoryGetCurrentUsage(&before));
  PetscCall(PetscTime(&t0));
  PetscCall(MatSetPreallocationCOO(A, count, rows, cols));
  PetscCall(MatSetValuesCOO(A, values, INSERT_VALUES));
  PetscCall(PetscTime(&t1));
  PetscCall(PetscFree3(rows, cols, values));
  PetscCall(PetscMemoryGetCurrentUsage(&assembled));

  Vec x, b;
  PetscCall(MatCreateVecs(A, &x, &b));
  PetscCall(VecSet(b, 1.0));
  KSP ksp;
  PetscCall(KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetFromOptions(ksp));
  PetscCall(PetscTime(&t2));
  PetscCall(KSPSetUp(ksp));
  PetscCall(KSPSolve(ksp, b, x));
  PetscCall(PetscTime(&t3));
  PetscCall(PetscMemoryGetCurrentUsage(&solved));
  PetscInt iterations;
  PetscCall(KSPGetIterationNumber(ksp, &iterations));
  MatInfo info;
  PetscCall(MatGetInfo(A, MAT_GLOBAL_SUM, &info));

  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "sizeof(PetscInt) %d, n %" PetscInt_FMT ", entries %.0f; rank 0: matrix %.1f MB (%.1f B "
                        "per row), solver %.1f MB (%.1f B per row); assembly %.2f s, setup + solve %.2f s, "
                        "%" PetscInt_FMT " iterations\n",
                        (int)sizeof(PetscInt), n, info.nz_used, (assembled - before) / 1e6,
                        (assembled - before) / local, (solved - assembled) / 1e6, (solved - assembled) / local, t1 - t0,
                        t3 - t2, iterations));
  PetscCall(KSPDestroy(&ksp));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(MatDestroy(&A));
  PetscCall(PetscFinalize());
  return 0;
}

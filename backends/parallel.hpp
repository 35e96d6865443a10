#pragma once
// The process's place among MPI ranks, for front ends that run the same command on every rank (the
// PETSc backends) and must write outputs and print results once. Without PETSc (or without
// mpirun) there is one process, rank 0.
namespace corrlap {

/// This process's rank in MPI_COMM_WORLD: from MPI when it is initialized, else from the launcher's
/// environment (Open MPI, MPICH, PMIx), so that it is known before the first solver starts MPI.
/// Always 0 in a build without PETSc.
int process_rank();

/// Whether this process writes the outputs and prints the results: rank 0.
inline bool is_output_rank() { return process_rank() == 0; }

}  // namespace corrlap

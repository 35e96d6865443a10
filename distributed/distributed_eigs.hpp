#pragma once
// The eigenvalue problem of `corrlap eigs` (docs/math.md §10.5: the k smallest mu = -lambda of
// L u = lambda M u) on a DistributedFem, solved by the slepc backend on the distributed L and M:
// no rank gathers a matrix.
#include <corrlap/backends/petsc.hpp>
#include <corrlap/core/linear_solver.hpp>

#include "distributed_fem.hpp"

namespace corrlap {

/// The slepc solver's solve_distributed on fem's L and M, with the options it was configured with.
/// Every rank gets the values (ascending). `vectors` is #owned by k: the rows of this rank's owned
/// vertices (DistributedSurface::vertex_ids maps them to serial ids), M-orthonormal over all ranks;
/// gather_on_rank0 (distributed_poisson.hpp) collects a column in serial order for writing.
/// Collective.
EigenResult distributed_eigs(const DistributedFem& fem, int k, SlepcEigenSolver& solver);

}  // namespace corrlap

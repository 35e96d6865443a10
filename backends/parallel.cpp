#include "parallel.hpp"

#include <cstdlib>
#include <string>

#if defined(CORRLAP_WITH_PETSC)
#include <mpi.h>
#endif

namespace corrlap {

int process_rank() {
#if defined(CORRLAP_WITH_PETSC)
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (initialized != 0 && finalized == 0) {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
  }
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"})
    if (const char* value = std::getenv(name); value != nullptr && *value != '\0') return std::atoi(value);
#endif
  return 0;
}

}  // namespace corrlap

#include "collectives.hpp"

#include <mpi.h>

#include "detail/owned_vectors.hpp"

namespace corrlap {

std::string text_of_rank0(const std::string& text) {
  int length = int(text.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string out = text;
  out.resize(std::size_t(length));
  MPI_Bcast(out.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
  return out;
}

double max_over_ranks(double x) { return detail::global_max(x); }

}  // namespace corrlap

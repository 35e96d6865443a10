#pragma once
// Small collective steps the commands take on the distributed front end (every rank of
// MPI_COMM_WORLD calls them together), so that the commands need no MPI of their own.
#include <string>

namespace corrlap {

/// Rank 0's `text` on every rank (e.g. the folder rank 0 created for the outputs).
std::string text_of_rank0(const std::string& text);

/// The largest of `x` over the ranks.
double max_over_ranks(double x);

}  // namespace corrlap

#pragma once
// Fill-reducing elimination order from the positions of the unknowns (internal): nested dissection
// by coordinate planes. The systems here are Laplacians of surfaces embedded in R^3; a plane through
// the median of the longest side cuts such a surface along a curve of O(sqrt n) unknowns, the kind of
// separator METIS finds by graph coarsening, in a small fraction of its time. Factor flops and
// ordering times against AMD and METIS: bench/RESULTS.md, "Scale on one machine".
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <vector>

namespace corrlap::detail {

/// The elimination order of the n unknowns of A (n x n, symmetric pattern stored in full; values are
/// not read) with positions `points` (n x 3): order[k] is the unknown eliminated k-th. Recursively,
/// the unknowns of a part are split at the median of their longest bounding-box side; the unknowns of
/// the upper half that have a neighbour (an entry of A) in the lower half form the separator, which
/// is eliminated after both halves. Parts of at most `leaf_size` unknowns keep their order. Large
/// parts order their halves as parallel TBB tasks; the result does not depend on the threads.
/// A permutation of 0..n-1 for any input (ties and disconnected parts included).
std::vector<int> geometric_nested_dissection(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixX3d& points,
                                             int leaf_size = 64);

}  // namespace corrlap::detail

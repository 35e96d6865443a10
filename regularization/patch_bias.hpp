#pragma once
// docs/math.md §9.5: the attachment bias of the regularization at one alpha (attachment_bias.hpp)
// estimated from solves on a few patches of the surface instead of one on the whole. The automatic
// alpha0 uses it on large surfaces to skip the first solve when its result would not be kept.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <corrlap/regularization/attachment_bias.hpp>

namespace corrlap {

/// Surfaces of fewer vertices have their first trial solved whole: the default patches would cover
/// a large part of them, and the whole solve costs little more.
inline constexpr Eigen::Index kPatchBiasMinVertices = 400000;
/// The first trial is skipped when its estimated bias is at least this many times the limit: far
/// beyond the estimate's sampling error (bench/RESULTS.md, "The first trial of the automatic alpha0
/// from patches"), so a result that could be kept is always solved.
inline constexpr double kPatchBiasSkipFactor = 4.0;

struct PatchBiasOptions {
  int patches = 128;  ///< patches, seeded at vertices spread evenly over the vertex order
  /// Rings (of L's graph) around a seed over which the bias is averaged.
  int core_rings = 8;
  /// Decay lengths of the solve's response added between the rings the bias reads and the patch's
  /// edge. 0 by default: the edge is held at the staircase, which the solve's result stays near,
  /// and margins hardly moved the estimate (bench/RESULTS.md) while multiplying its cost.
  double margin_lengths = 0.0;
  int rounds = kAttachmentBiasRounds;  ///< as attachment_bias
  double accuracy = 0.01;              ///< of each patch's solve, in steps (regularize_positions_preconditioned)
  /// The patches are solved in 4 rounds, each spread over the surface; after a round, an estimate
  /// below this stops (0: never). The automatic alpha0 passes half its skip threshold: a smooth
  /// surface, whose first trial is solved anyway, pays a quarter of the patches.
  double stop_below = 0.0;
};

/// The rings of L's graph a patch spans at this alpha: the core, the smoothing's rounds, and the
/// margin, margin_lengths times the decay length sqrt(2) alpha^(-1/4) of the regularization's
/// response (docs/math.md §9.5), in steps (a ring is at least one step of the grid).
int patch_rings(double alpha, double step, const PatchBiasOptions& options = {});

struct PatchBias {
  double bias = 0.0;               ///< the estimate of attachment_bias, in steps
  int patches = 0;                 ///< solved (fewer than asked after a stop_below)
  Eigen::Index vertices = 0;       ///< solved for, over every patch (a vertex in two counts twice)
  Eigen::Index core_vertices = 0;  ///< averaged over, over every patch
};

/// The mass-weighted mean of attachment_bias's |s| over the cores of `options.patches` patches,
/// each regularized alone at `alpha`: the vertices within patch_rings of its seed move, every other
/// vertex is held at the staircase (the energy of docs/math.md §9.2 restricted to the patch's
/// displacements, whose matrix is L's principal submatrix). The smoothing of a core vertex reads
/// `rounds` rings around it, all inside the patch. With one patch covering a whole component it is
/// attachment_bias of that component's solve; otherwise its error is mostly the sampling of the
/// cores. Arguments as attachment_bias and regularize_positions_preconditioned. The patches are
/// solved in parallel (TBB), each with Eigen's simplicial Cholesky; the sum over them is taken in
/// their order, so the estimate does not depend on the threads. InputError on mismatched sizes.
PatchBias patch_attachment_bias(const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& faces,
                                const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                const Eigen::MatrixX3d& staircase, const Eigen::MatrixX3d& normals,
                                const Eigen::VectorXd& H, double alpha, double step,
                                const PatchBiasOptions& options = {});

}  // namespace corrlap

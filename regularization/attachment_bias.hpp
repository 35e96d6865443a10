#pragma once
// The attachment weight chosen from the data (docs/math.md §9.4): the regularization should move
// the staircase only within its own quantization noise. Where the result keeps away from the
// staircase's local mean, the curvature target has smoothed detail the surface has, and alpha0 is
// raised until the local mean is kept.
#include <Eigen/Core>
#include <vector>

namespace corrlap {

/// The bias limit, in steps of the positions' error: the analytic shapes of bench/compare_surfaces.py
/// (smooth at the voxel scale) stay below it with alpha0 = 10, voxelized models with detail a few
/// voxels wide are far above it (bench/RESULTS.md, "The attachment weight chosen from the data").
inline constexpr double kAttachmentBiasLimit = 0.02;
/// Rounds of 1-ring averaging in attachment_bias: a window of a few voxels, wide enough to average
/// the staircase's quantization away and narrow enough to see detail of that size.
inline constexpr int kAttachmentBiasRounds = 16;
/// The automatic choice solves at most this many times ...
inline constexpr int kAutoAlpha0MaxSolves = 4;
/// ... and raises alpha0 at most until the result follows the staircase at every wavelength longer
/// than this many steps (alpha0_for_wavelength).
inline constexpr double kAutoAlpha0MinWavelength = 2.0;
/// A raise of alpha0 is kept only if the bias fell at least like alpha0^-kAutoAlpha0MinSlope: detail
/// the curvature ball smoothed comes back fast (about alpha0^-0.4), the bias of a smooth shape's
/// staircase near the limit hardly moves (about alpha0^-0.1), and raising alpha0 there only adds
/// the stairs back.
inline constexpr double kAutoAlpha0MinSlope = 0.2;

/// The alpha0 at which the regularization's filter hands over from the staircase to the curvature
/// target at `wavelength` steps, on a surface of size `size_steps` steps: with -L u = lambda M u
/// and lambda = (2 pi / l)^2 for a wave of length l, the two terms weigh the same where
/// lambda^2 = alpha = alpha0 / (h size)^2, so alpha0 = (2 pi / wavelength)^4 size_steps^2.
double alpha0_for_wavelength(double wavelength, double size_steps);

/// The mean local bias of `result` against `staircase` along the normals, in units of `step`:
/// s_v = n_v . (staircase_v - result_v) / step, smoothed by `rounds` rounds of
/// s_v <- (s_v + sum over the face edges (v, w) of s_w) / (1 + their count) (an edge shared by two
/// faces counts twice), then the mass-weighted mean of |s_v|.
///   faces      #F by 4 vertex ids (quads; any closed or open polygon mesh given as quads)
///   staircase  #V by 3 input positions
///   result     #V by 3 regularized positions
///   normals    #V by 3 unit normals
///   mass       #V vertex masses, the weights of the mean (>= 0, some > 0: 0 leaves a vertex out of
///              the mean, not out of the smoothing)
double attachment_bias(const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& faces,
                       const Eigen::MatrixX3d& staircase, const Eigen::MatrixX3d& result,
                       const Eigen::MatrixX3d& normals, const Eigen::VectorXd& mass, double step,
                       int rounds = kAttachmentBiasRounds);

/// One trial of the automatic choice: the alpha0 solved with and the bias of its result, or, when
/// `estimated`, the bias estimated from patches without a solve (patch_bias.hpp).
struct Alpha0Trial {
  double alpha0 = 0.0, bias = 0.0;
  bool estimated = false;
};

/// The slope of the bias against alpha0 in log-log between trials a and b (a solved first):
/// log(bias_a / bias_b) / log(alpha0_b / alpha0_a); 0 where it is not defined.
double bias_slope(const Alpha0Trial& a, const Alpha0Trial& b);

/// The next alpha0 to try after `trials` (in the order solved), or 0 when the search stops: the
/// last bias is within `limit`, the last raise bought less than kAutoAlpha0MinSlope, the last
/// alpha0 reached `largest`, or the solves are used up. The bias falls like a power of alpha0: the
/// next alpha0 is where the line through the last two trials in log-log (slope 0.4 after the
/// first) meets 0.8 limit, at least 1.5 and at most 10 000 times the last, and at most `largest`.
double next_alpha0(const std::vector<Alpha0Trial>& trials, double limit, double largest,
                   int max_solves = kAutoAlpha0MaxSolves);

/// Which trial's result to keep: the last, or the one before it when the last raise bought less
/// than kAutoAlpha0MinSlope.
std::size_t chosen_alpha0_trial(const std::vector<Alpha0Trial>& trials);

}  // namespace corrlap

#pragma once
// The check every regularization and reconstruction result passes before it leaves the library:
// finite, not collapsed nor blown up against its input, and the solve's residual small. A solve
// can "succeed" into nonsense (an attachment weight beyond what double precision holds gives
// every vertex at the origin); the check turns that into an error with the numbers.
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <optional>
#include <string>

namespace corrlap {

/// The result against the input.
struct SolutionCheck {
  double area_ratio = 1.0;    ///< area of the result / area of the input (surface_area)
  double extent_ratio = 1.0;  ///< smallest over the axes of the result's bounding-box side / the input's
  /// Relative residual of the solve, max over the coordinates of |b - A q| / |b|; none for a
  /// result that is not one linear solve (the alignment descent) or whose solve proved its
  /// accuracy by an error bound (regularize_positions_preconditioned with an accuracy).
  std::optional<double> residual;
  /// "area ratio A, extent ratio E, residual R", for messages and reports.
  std::string describe() const;
};

/// Measures `result` (#V x 3, positions for `input`'s faces) against `input` and throws
/// NumericalError, starting with `what` and giving the numbers and a hint, when a position is not
/// finite, the area ratio leaves [kMinAreaRatio, kMaxAreaRatio], the extent ratio falls below
/// kMinExtentRatio or the residual exceeds kMaxResidual. Returns the measures otherwise.
SolutionCheck check_solution(const SurfelMesh& input, const Eigen::MatrixX3d& result, std::optional<double> residual,
                             const std::string& what);

/// check_solution's judgement of measures taken elsewhere (the distributed front end sums them over
/// its ranks): throws its NumericalError when they leave the bounds, returns them otherwise.
SolutionCheck judge_solution(const SolutionCheck& measures, const std::string& what);

/// The bounds of check_solution (bench/RESULTS.md, "regularization solution check": the margins
/// measured over the paper's alpha0 range on sphere1).
inline constexpr double kMinAreaRatio = 0.2, kMaxAreaRatio = 5.0, kMinExtentRatio = 0.5, kMaxResidual = 1e-3;

}  // namespace corrlap

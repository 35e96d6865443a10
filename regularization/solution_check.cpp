#include "solution_check.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <limits>
#include <sstream>

namespace corrlap {

std::string SolutionCheck::describe() const {
  std::ostringstream os;
  os.precision(3);
  os << "area ratio " << area_ratio << ", extent ratio " << extent_ratio;
  if (residual) os << ", residual " << *residual;
  return os.str();
}

SolutionCheck check_solution(const SurfelMesh& input, const Eigen::MatrixX3d& result, std::optional<double> residual,
                             const std::string& what) {
  if (result.rows() != input.num_vertices())
    throw InputError(what + ": " + std::to_string(result.rows()) + " positions for " +
                     std::to_string(input.num_vertices()) + " vertices");
  for (Eigen::Index v = 0; v < result.rows(); ++v)
    if (!result.row(v).allFinite())
      throw NumericalError(what + ": the position of vertex " + std::to_string(v) +
                           " is not finite; the solve broke down (check alpha0 and the normals)");
  SolutionCheck c;
  c.residual = residual;
  SurfelMesh out = input;
  out.positions = result;
  const double area_before = surface_area(input);
  c.area_ratio = area_before > 0.0 ? surface_area(out) / area_before : 1.0;
  const Eigen::RowVector3d side_before = input.positions.colwise().maxCoeff() - input.positions.colwise().minCoeff();
  const Eigen::RowVector3d side_after = result.colwise().maxCoeff() - result.colwise().minCoeff();
  c.extent_ratio = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k)
    if (side_before[k] > 0.0) c.extent_ratio = std::min(c.extent_ratio, side_after[k] / side_before[k]);
  if (!std::isfinite(c.extent_ratio)) c.extent_ratio = 1.0;  // a point: no extent to compare
  return judge_solution(c, what);
}

SolutionCheck judge_solution(const SolutionCheck& c, const std::string& what) {
  const std::optional<double>& residual = c.residual;
  const bool collapsed = c.area_ratio < kMinAreaRatio || c.extent_ratio < kMinExtentRatio;
  const bool blown_up = c.area_ratio > kMaxAreaRatio;
  const bool inaccurate = residual && !(*residual <= kMaxResidual);
  if (!collapsed && !blown_up && !inaccurate) return c;
  std::ostringstream os;
  os << what << ": the result "
     << (collapsed  ? "collapsed"
         : blown_up ? "blew up"
                    : "is not the solution of its system")
     << " (" << c.describe() << "; a regularized surface keeps its area within [" << kMinAreaRatio << ", "
     << kMaxAreaRatio << "] and its extent above " << kMinExtentRatio << " of the input's";
  if (residual) os << ", its residual below " << kMaxResidual;
  os << "); the solve is off its range: use alpha0 within the paper's 0.01 to 1000, check the normals (a smaller II "
        "radius for a small object) and clamp the mean curvature (h_clamp)";
  throw NumericalError(os.str());
}

}  // namespace corrlap

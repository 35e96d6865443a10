#include "attachment_bias.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <numbers>
#include <string>

namespace corrlap {

double attachment_bias(const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& faces,
                       const Eigen::MatrixX3d& staircase, const Eigen::MatrixX3d& result,
                       const Eigen::MatrixX3d& normals, const Eigen::VectorXd& mass, double step, int rounds) {
  const Eigen::Index n = staircase.rows();
  if (result.rows() != n || normals.rows() != n || mass.size() != n)
    throw InputError("attachment_bias: staircase, result, normals and mass need one row per vertex (" +
                     std::to_string(n) + ")");
  if (!(step > 0.0) || !std::isfinite(step)) throw InputError("attachment_bias: the step must be a positive number");
  if (rounds < 0) throw InputError("attachment_bias: the number of rounds must be >= 0");
  if (n == 0) return 0.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 4; ++k)
      if (faces(f, k) < 0 || faces(f, k) >= n)
        throw InputError("attachment_bias: face " + std::to_string(f) + " has a vertex id out of range");
  Eigen::VectorXd s = ((staircase - result).cwiseProduct(normals)).rowwise().sum() / step;
  Eigen::VectorXd count = Eigen::VectorXd::Ones(n);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) {
      count[faces(f, k)] += 1.0;
      count[faces(f, (k + 1) % 4)] += 1.0;
    }
  Eigen::VectorXd next(n);
  for (int round = 0; round < rounds; ++round) {
    next = s;
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
      for (int k = 0; k < 4; ++k) {
        const int a = faces(f, k), b = faces(f, (k + 1) % 4);
        next[a] += s[b];
        next[b] += s[a];
      }
    s = next.cwiseQuotient(count);
  }
  const double total = mass.sum();
  if (!(total > 0.0)) throw InputError("attachment_bias: the masses must sum to a positive number");
  return s.cwiseAbs().dot(mass) / total;
}

double alpha0_for_wavelength(double wavelength, double size_steps) {
  if (!(wavelength > 0.0) || !(size_steps > 0.0))
    throw InputError("alpha0_for_wavelength: the wavelength and the size must be positive");
  const double k = 2.0 * std::numbers::pi / wavelength;
  return k * k * k * k * size_steps * size_steps;
}

double bias_slope(const Alpha0Trial& a, const Alpha0Trial& b) {
  if (!(a.alpha0 > 0.0) || !(b.alpha0 > a.alpha0) || !(a.bias > 0.0) || !(b.bias > 0.0)) return 0.0;
  return std::log(a.bias / b.bias) / std::log(b.alpha0 / a.alpha0);
}

double next_alpha0(const std::vector<Alpha0Trial>& trials, double limit, double largest, int max_solves) {
  if (trials.empty() || int(trials.size()) >= max_solves) return 0.0;
  const Alpha0Trial& last = trials.back();
  if (!(last.bias > limit) || !(last.alpha0 > 0.0) || last.alpha0 >= largest) return 0.0;
  double slope = 0.4;
  if (trials.size() >= 2) {
    slope = bias_slope(trials[trials.size() - 2], last);
    if (slope < kAutoAlpha0MinSlope) return 0.0;
  }
  const double factor = std::clamp(std::pow(last.bias / (0.8 * limit), 1.0 / slope), 1.5, 1e4);
  return std::min(last.alpha0 * factor, largest);
}

std::size_t chosen_alpha0_trial(const std::vector<Alpha0Trial>& trials) {
  if (trials.size() < 2) return 0;
  const std::size_t last = trials.size() - 1;
  return bias_slope(trials[last - 1], trials[last]) < kAutoAlpha0MinSlope ? last - 1 : last;
}

}  // namespace corrlap

#pragma once
// Wall-clock seconds of the stages that reports and benchmarks print (the one timing helper of the
// project: solver reports, regularization stages, studies, CLI and benchmark tables).
#include <chrono>

namespace corrlap {

/// Wall-clock time (steady clock) since construction or the last lap() / restart().
/// `elapsed()` reads it and leaves the start where it is (the time of one whole stage, read once or
/// more); `lap()` reads it and restarts, so consecutive laps time consecutive stages:
///   Stopwatch watch;  read(); double read_s = watch.lap();  solve(); double solve_s = watch.lap();
class Stopwatch {
 public:
  using Clock = std::chrono::steady_clock;

  Stopwatch() : start_(Clock::now()) {}

  /// Seconds since the start; the start is unchanged.
  double elapsed() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  /// Seconds since the start, and the start moves to now.
  double lap() {
    const auto now = Clock::now();
    const double seconds = std::chrono::duration<double>(now - start_).count();
    start_ = now;
    return seconds;
  }

  /// Starts again from now (the time in between is not counted anywhere).
  void restart() { start_ = Clock::now(); }

 private:
  Clock::time_point start_;
};

}  // namespace corrlap

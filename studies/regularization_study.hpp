#pragma once
// The regularization study (paper §4.1, Fig. 13 and 15; docs/regularization.md): implicit shapes
// digitized at several resolutions, regularized by each method (a corrected calculus, the uncorrected
// PolyDEC, or the baseline [17]) at each attachment weight alpha0, and the result measured against the
// true surface.
#include <functional>
#include <string>
#include <vector>

namespace corrlap {

struct RegularizationStudyOptions {
  std::vector<std::string> shapes = {"sphere1", "torus", "goursat"};  ///< implicit shapes (make_implicit_shape)
  /// Voxels along each shape's longest side: h = (its longest side) / N, so that every shape is
  /// resolved alike whatever its size. Ignored when `h` is given.
  std::vector<int> resolutions = {32, 64, 128};
  std::vector<double> h;  ///< grid steps used for every shape instead (world units)
  /// Vertex discretizations of the registry (docs/math.md §9.2), or "alignment": the paper's
  /// baseline [17] (docs/math.md §9.1, the reference's descent with its defaults).
  std::vector<std::string> methods = {"fem", "polydec", "alignment"};
  /// A normal source (parse_normal_source): "ii" (the paper's, alpha = 1/3) or "true"; the baseline
  /// gets the face normals
  std::string normals = "ii";
  /// Attachment weights swept (as RegularizationOptions::alpha0, each >= 0; 0: no attachment, paper
  /// Fig. 11); the baseline has none and runs once per (shape, h).
  std::vector<double> alpha0 = {10.0};
  double min_aabb = -10.0, max_aabb = 10.0;  ///< digitization box of every shape
  int offset = 5;
  std::string linear_solver = "cholmod";
  /// InputError naming the first invalid option (unknown shape or method, no resolution...).
  void validate() const;
};

/// One (shape, h, alpha0, method): the quality of the staircase and of the regularized surface
/// (measure_against_shape, regularization/surface_quality.hpp).
struct RegularizationStudyRow {
  std::string shape, method, normals;
  double h = 0;
  int resolution = 0;  ///< N when the study runs by resolutions, else 0
  double alpha0 = 0;   ///< NaN for the baseline (no attachment weight)
  long long vertices = 0, faces = 0;
  double distance_before = 0, distance_after = 0;  ///< mean vertex distance to the true surface
  double angle_before = 0, angle_after = 0;        ///< mean vertex normal angle to the true normals, degrees
  double curvature_error_before = 0, curvature_error_after = 0;  ///< mean |H - H_true|
  double area_before = 0, area_after = 0;
  double volume_before = 0, volume_after = 0;  ///< enclosed (surface_quality.hpp)
  /// The method's regularization (normals and digitization excluded); the first Laplacian method
  /// of an (shape, h) also carries the corrected curvature, which the others reuse.
  double time_s = 0;
};

struct RegularizationStudyProgress {
  int done = 0, total = 0;
  std::string shape, method;
  double h = 0;
  double alpha0 = 0;  ///< NaN for the baseline
};

/// Runs the study: per (shape, h) the digitization, the normals, the curvature and the quality of
/// the staircase once; then every method at every alpha0 (the baseline once). Rows reach `row` as they are made. Throws
/// InputError for bad options, the method's errors naming the shape, h and method.
void run_regularization_study(const RegularizationStudyOptions& options,
                              const std::function<void(const RegularizationStudyRow&)>& row,
                              const std::function<void(const RegularizationStudyProgress&)>& progress = {});

/// The study's CSV (one row per (shape, h, alpha0, method), 17 significant digits; the baseline's
/// alpha0 empty), and reading it back.
void write_regularization_csv(const std::string& path, const std::vector<RegularizationStudyRow>& rows);
std::vector<RegularizationStudyRow> read_regularization_csv(const std::string& path);

}  // namespace corrlap

#include "regularization_study.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_checks.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <corrlap/regularization/alignment_regularization.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <optional>
#include <sstream>

#include "detail/csv.hpp"
#include "detail/repeats.hpp"

namespace corrlap {

namespace {

constexpr const char* kHeader =
    "study,shape,method,normals,h,resolution,alpha0,vertices,faces,distance_before,distance_after,angle_before,"
    "angle_after,curvature_error_before,curvature_error_after,area_before,area_after,volume_before,volume_after,time_s";

DigitizationParams box(const RegularizationStudyOptions& o, double h) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = o.min_aabb;
  p.max_aabb = o.max_aabb;
  p.offset = o.offset;
  return p;
}

// The longest side of the shape's digitization at a coarse step (1/96 of the box): the scale that
// `resolutions` divide. Within two coarse voxels of the true extent.
double longest_side(const ImplicitShape& shape, const RegularizationStudyOptions& o, const std::string& name) {
  const VoxelGrid grid = digitize(shape, box(o, (o.max_aabb - o.min_aabb) / 96.0));
  if (grid.count() == 0)
    throw InputError("study regularization: shape '" + name + "' has no voxel inside the box [" +
                         std::to_string(o.min_aabb) + ", " + std::to_string(o.max_aabb) + "]^3 (give a box)",
                     "bbox");
  const SurfelMesh coarse = extract_surface(grid);
  return (coarse.positions.colwise().maxCoeff() - coarse.positions.colwise().minCoeff()).maxCoeff();
}

}  // namespace

void RegularizationStudyOptions::validate() const {
  if (shapes.empty()) throw InputError("study regularization: no shape", "shapes");
  for (const std::string& s : shapes) (void)make_implicit_shape(s);  // InputError listing the names
  if (methods.empty()) throw InputError("study regularization: no method", "methods");
  for (const std::string& m : methods)
    if (m != "alignment") (void)make_discretization(m);  // InputError listing the registry
  if (h.empty() && resolutions.empty()) throw InputError("study regularization: no resolution and no h");
  for (int n : resolutions)
    if (h.empty() && (n < 8 || n > 2048))
      throw InputError("study regularization: resolution " + std::to_string(n) + " is outside [8, 2048]");
  for (double x : h)
    if (!(x > 0.0) || !std::isfinite(x)) throw InputError("study regularization: h must be positive", "h");
  detail::refuse_repeats(shapes, "shape", "shapes", "study regularization");
  detail::refuse_repeats(methods, "method", "methods", "study regularization");
  detail::refuse_repeats(h, "grid step h =", "h", "study regularization");
  if (h.empty()) detail::refuse_repeats(resolutions, "resolution", "resolutions", "study regularization");
  if (normals != to_string(NormalSource::II) && normals != to_string(NormalSource::True))
    throw InputError("study regularization: normals '" + normals + "': expected ii or true", "normals");
  if (alpha0.empty()) throw InputError("study regularization: no alpha0", "alpha0");
  for (double a : alpha0)
    if (!(a >= 0.0) || !std::isfinite(a)) {
      std::ostringstream os;
      os << "study regularization: alpha0 must be a finite number >= 0 (0: no attachment), got " << a;
      throw InputError(os.str(), "alpha0");
    }
  detail::refuse_repeats(alpha0, "alpha0 =", "alpha0", "study regularization");
  if (!(max_aabb > min_aabb)) throw InputError("study regularization: the box must have max > min");
}

void run_regularization_study(const RegularizationStudyOptions& o,
                              const std::function<void(const RegularizationStudyRow&)>& row,
                              const std::function<void(const RegularizationStudyProgress&)>& progress) {
  o.validate();
  RegularizationStudyProgress p;
  const auto laplacians =
      std::count_if(o.methods.begin(), o.methods.end(), [](const std::string& m) { return m != "alignment"; });
  const auto per_step = std::size_t(laplacians) * o.alpha0.size() + (o.methods.size() - std::size_t(laplacians));
  p.total = int(o.shapes.size() * (o.h.empty() ? o.resolutions.size() : o.h.size()) * per_step);
  for (const std::string& name : o.shapes) {
    const ImplicitShape shape = make_implicit_shape(name);
    std::vector<std::pair<double, int>> steps;  // (h, resolution)
    if (!o.h.empty()) {
      for (double h : o.h) steps.emplace_back(h, 0);
    } else {
      const double side = longest_side(shape, o, name);
      for (int n : o.resolutions) steps.emplace_back(side / n, n);
    }
    for (const auto& [h, resolution] : steps) {
      ImplicitShapeInput input;
      input.shape = name;
      input.digitization = box(o, h);
      LoadedSurface surface;
      try {
        surface = load_surface(input);
        check_regularizable(surface.mesh);
      } catch (const InputError& e) {
        std::ostringstream os;
        os << "study regularization: " << name << " at h = " << h << ": " << e.what();
        throw InputError(os.str(), e.parameter());
      }
      const SurfelMesh& mesh = surface.mesh;
      NormalRequest request;
      request.source = parse_normal_source(o.normals);
      const NormalFields normals = resolve_normals(surface, NormalKind::Vertex, request, "study");
      // The quality of both surfaces with the curvature radius of the regularization.
      const double radius = default_curvature_radius(surface);
      const SurfaceQuality before = measure_against_shape(mesh, shape, radius);
      const double area_before = surface_area(mesh);
      const double volume_before = enclosed_volume(mesh);
      RegularizationOptions options;
      options.alpha0_auto = false;  // the paper's protocol: each alpha0 swept as it is
      options.solver.set("solver", o.linear_solver);
      std::optional<RegularizationCurvature> curvature;  // the same for every Laplacian method and alpha0
      for (const std::string& method : o.methods) {
        // The baseline has no attachment weight: one unit, alpha0 NaN.
        const std::vector<double> weights = method == "alignment" ? std::vector<double>{detail::kNaN} : o.alpha0;
        for (const double alpha0 : weights) {
          const Stopwatch watch;
          SurfelMesh result = mesh;
          try {
            if (method == "alignment") {
              result.positions = alignment_regularization(mesh, normals.face).positions;
            } else {
              options.method = method;
              options.alpha0 = alpha0;
              if (!curvature) curvature = regularization_curvature(surface, normals, options);
              result = regularize_surface(surface, normals, options, &*curvature).mesh;
            }
          } catch (const Error& e) {
            std::ostringstream os;
            os << "study regularization: " << name << " at h = " << h << ", " << method;
            if (method != "alignment") os << ", alpha0 = " << alpha0;
            os << ": " << e.what();
            if (dynamic_cast<const InputError*>(&e)) throw InputError(os.str());
            throw NumericalError(os.str());
          }
          RegularizationStudyRow r;
          r.time_s = watch.elapsed();
          r.shape = name;
          r.method = method;
          r.normals = o.normals;
          r.h = h;
          r.resolution = resolution;
          r.alpha0 = alpha0;
          r.vertices = mesh.num_vertices();
          r.faces = mesh.num_faces();
          const SurfaceQuality after = measure_against_shape(result, shape, radius);
          r.distance_before = before.distance_l1;
          r.distance_after = after.distance_l1;
          r.angle_before = before.normal_angle_deg;
          r.angle_after = after.normal_angle_deg;
          r.curvature_error_before = before.mean_curvature_error;
          r.curvature_error_after = after.mean_curvature_error;
          r.area_before = area_before;
          r.area_after = surface_area(result);
          r.volume_before = volume_before;
          r.volume_after = enclosed_volume(result);
          if (row) row(r);
          ++p.done;
          p.shape = name;
          p.method = method;
          p.h = h;
          p.alpha0 = alpha0;
          if (progress) progress(p);
        }
      }
    }
  }
}

void write_regularization_csv(const std::string& path, const std::vector<RegularizationStudyRow>& rows) {
  std::FILE* f = detail::open_csv(path, false, kHeader);
  using detail::number;
  for (const RegularizationStudyRow& r : rows)
    std::fprintf(f, "regularization,%s,%s,%s,%s,%d,%s,%lld,%lld,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", r.shape.c_str(),
                 r.method.c_str(), r.normals.c_str(), number(r.h).c_str(), r.resolution, number(r.alpha0).c_str(),
                 r.vertices, r.faces, number(r.distance_before).c_str(), number(r.distance_after).c_str(),
                 number(r.angle_before).c_str(), number(r.angle_after).c_str(),
                 number(r.curvature_error_before).c_str(), number(r.curvature_error_after).c_str(),
                 number(r.area_before).c_str(), number(r.area_after).c_str(), number(r.volume_before).c_str(),
                 number(r.volume_after).c_str(), number(r.time_s).c_str());
  detail::close_csv(f, path);
}

std::vector<RegularizationStudyRow> read_regularization_csv(const std::string& path) {
  const detail::CsvReader csv(path, kHeader);
  std::vector<RegularizationStudyRow> out;
  for (const auto& row : csv.rows()) {
    RegularizationStudyRow r;
    r.shape = row.fields[1];
    r.method = row.fields[2];
    r.normals = row.fields[3];
    r.h = csv.required_number(row, 4);
    r.resolution = int(csv.required_integer(row, 5));
    r.alpha0 = csv.number(row, 6);
    r.vertices = csv.required_integer(row, 7);
    r.faces = csv.required_integer(row, 8);
    r.distance_before = csv.number(row, 9);
    r.distance_after = csv.number(row, 10);
    r.angle_before = csv.number(row, 11);
    r.angle_after = csv.number(row, 12);
    r.curvature_error_before = csv.number(row, 13);
    r.curvature_error_after = csv.number(row, 14);
    r.area_before = csv.number(row, 15);
    r.area_after = csv.number(row, 16);
    r.volume_before = csv.number(row, 17);
    r.volume_after = csv.number(row, 18);
    r.time_s = csv.number(row, 19);
    out.push_back(r);
  }
  return out;
}

}  // namespace corrlap

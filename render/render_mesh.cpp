#include "render_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <cstdio>
#include <limits>
#include <span>
#include <vector>

#include "detail/bitmap_font.hpp"

namespace corrlap {

namespace {

// Orthonormal screen frame: x to the right, y up, z towards the viewer (larger depth = nearer).
struct Camera {
  Eigen::Vector3d right, up, toward;
};

Camera make_camera(const Eigen::Vector3d& view, const Eigen::Vector3d& up) {
  if (!view.allFinite() || view.norm() == 0.0) throw InputError("render: the view direction must be a nonzero vector");
  if (!up.allFinite() || up.norm() == 0.0) throw InputError("render: the up direction must be a nonzero vector");
  Camera c;
  c.toward = view.normalized();
  Eigen::Vector3d u = up - up.dot(c.toward) * c.toward;
  if (u.norm() < 1e-6 * up.norm()) {  // up along the view: take the axis least aligned with it
    Eigen::Index axis;
    c.toward.cwiseAbs().minCoeff(&axis);
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(axis);
    u = e - e.dot(c.toward) * c.toward;
  }
  c.up = u.normalized();
  c.right = c.up.cross(c.toward);
  return c;
}

void check_size(const char* what, int value, int lo, int hi) {
  if (value < lo || value > hi)
    throw InputError(std::string("render: ") + what + " " + std::to_string(value) + " is outside [" +
                     std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

// Value at the q-quantile (0..1) of sorted values.
double quantile(const std::vector<double>& sorted, double q) {
  return sorted[std::size_t(std::floor(q * double(sorted.size() - 1)))];
}

void draw_text(Image& image, int x, int y, const std::string& text, int scale) {
  for (std::size_t k = 0; k < text.size(); ++k) {
    const auto rows = detail::glyph(text[k]);
    const int gx = x + int(k) * (detail::kGlyphWidth + 1) * scale;
    for (int r = 0; r < detail::kGlyphHeight; ++r)
      for (int col = 0; col < detail::kGlyphWidth; ++col) {
        if (!((rows[std::size_t(r)] >> (detail::kGlyphWidth - 1 - col)) & 1)) continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) {
            const int px = gx + col * scale + dx, py = y + r * scale + dy;
            if (px < 0 || py < 0 || px >= image.width || py >= image.height) continue;
            std::uint8_t* p = image.pixel(px, py);
            p[0] = p[1] = p[2] = 30;
          }
      }
  }
}

std::string format_number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", v == 0.0 ? 0.0 : v);  // no "-0"
  return buffer;
}

std::uint8_t to_byte(double c) { return std::uint8_t(std::lround(std::clamp(c, 0.0, 1.0) * 255.0)); }

// The colour bar in the panel [left, width) x [0, height): the maximum at the top.
void draw_legend(Image& image, int left, const ColourScale& scale, const std::string& name) {
  const int text_scale = std::max(1, image.height / 400);
  const int line = (detail::kGlyphHeight + 3) * text_scale;
  const int top = image.height / 6, bottom = image.height - image.height / 6;
  const int x0 = left + std::max(4, (image.width - left) / 10), bar_width = std::max(6, image.height / 40);
  for (int y = top; y <= bottom; ++y) {
    const double t = 1.0 - double(y - top) / double(std::max(1, bottom - top));
    const Eigen::Vector3d c = colormap_rgb(scale.map, t);
    for (int x = x0; x < x0 + bar_width && x < image.width; ++x) {
      std::uint8_t* p = image.pixel(x, y);
      p[0] = to_byte(c[0]);
      p[1] = to_byte(c[1]);
      p[2] = to_byte(c[2]);
    }
  }
  const int label_x = x0 + bar_width + 3 * text_scale;
  const int half_glyph = detail::kGlyphHeight * text_scale / 2;
  draw_text(image, label_x, top - half_glyph, format_number(scale.max), text_scale);
  draw_text(image, label_x, (top + bottom) / 2 - half_glyph, format_number(0.5 * (scale.min + scale.max)), text_scale);
  draw_text(image, label_x, bottom - half_glyph, format_number(scale.min), text_scale);
  draw_text(image, x0, std::max(0, top - 2 * line), name, text_scale);
}

}  // namespace

FieldPercentiles field_percentiles(const ScalarField& field) {
  if (field.values.size() == 0) throw InputError("render: scalar '" + field.name + "' has no value");
  for (Eigen::Index i = 0; i < field.values.size(); ++i)
    if (!std::isfinite(field.values[i]))
      throw InputError("render: scalar '" + field.name + "' is not finite at " +
                       (field.per_face ? "face " : "vertex ") + std::to_string(i));
  std::vector<double> sorted(field.values.data(), field.values.data() + field.values.size());
  std::sort(sorted.begin(), sorted.end());
  FieldPercentiles p;
  p.low = quantile(sorted, 0.02);
  p.high = quantile(sorted, 0.98);
  std::vector<double> magnitude(sorted.size());
  std::transform(sorted.begin(), sorted.end(), magnitude.begin(), [](double v) { return std::abs(v); });
  std::sort(magnitude.begin(), magnitude.end());
  p.magnitude_high = quantile(magnitude, 0.98);
  return p;
}

ColourScale colour_scale(const FieldPercentiles& p, const RenderOptions& options) {
  double lo = p.low, hi = p.high;
  if (lo < 0.0 && hi > 0.0) {  // both signs: symmetric about 0
    hi = p.magnitude_high;
    lo = -hi;
  }
  if (!(hi > lo)) {  // a constant field: a small range around it
    const double pad = lo != 0.0 ? 0.01 * std::abs(lo) : 1.0;
    lo -= pad;
    hi += pad;
  }
  ColourScale s;
  s.min = options.range_min.value_or(lo);
  s.max = options.range_max.value_or(hi);
  if (!std::isfinite(s.min) || !std::isfinite(s.max) || !(s.max > s.min))
    throw InputError("render: the colour range [" + format_number(s.min) + ", " + format_number(s.max) +
                     "] is empty (need min < max)");
  s.map = options.colormap.value_or(s.min < 0.0 && s.max > 0.0 ? Colormap::Diverging : Colormap::Sequential);
  return s;
}

ColourScale colour_scale(const ScalarField& field, const RenderOptions& options) {
  return colour_scale(field_percentiles(field), options);
}

void check_render_options(const RenderOptions& options) {
  check_size("width", options.width, 16, 8192);
  check_size("height", options.height, 16, 8192);
  check_size("supersampling", options.supersampling, 1, 4);
  const double samples = double(options.width) * options.height * options.supersampling * options.supersampling;
  if (samples > double(1 << 26))
    throw InputError(
        "render: " + std::to_string(options.width) + " x " + std::to_string(options.height) + " pixels with " +
        std::to_string(options.supersampling) + " x " + std::to_string(options.supersampling) + " supersampling are " +
        std::to_string(std::int64_t(samples)) + " samples, more than 67 M (2 GB); lower the size or the supersampling");
  (void)make_camera(options.view_direction, options.up);
}

ScreenExtent screen_extent(const Eigen::MatrixX3d& positions, const RenderOptions& options) {
  const Camera cam = make_camera(options.view_direction, options.up);
  ScreenExtent e;
  if (positions.rows() == 0) return e;
  const Eigen::VectorXd x = positions * cam.right, y = positions * cam.up;
  e.lo_x = x.minCoeff();
  e.hi_x = x.maxCoeff();
  e.lo_y = y.minCoeff();
  e.hi_y = y.maxCoeff();
  return e;
}

RenderSamples render_samples(const PolygonMesh& mesh, const ScalarField* field, const std::optional<ColourScale>& scale,
                             const ScreenExtent& extent, const RenderOptions& options,
                             const std::vector<std::int64_t>& face_ids) {
  check_render_options(options);
  const Eigen::Index nv = mesh.positions.rows();
  if (!mesh.positions.allFinite()) throw InputError("render: the mesh has a non-finite vertex position");
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.faces[f].size() < 3) throw InputError("render: face " + std::to_string(f) + " has fewer than 3 vertices");
    for (int v : mesh.faces[f])
      if (v < 0 || v >= nv)
        throw InputError("render: face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + " of " +
                         std::to_string(nv));
  }
  if (!face_ids.empty() && face_ids.size() != mesh.faces.size())
    throw InputError("render: expected one face id per face");
  if (field) {
    if (!scale) throw InputError("render: a coloured surface needs its colour scale");
    const Eigen::Index expected = field->per_face ? Eigen::Index(mesh.faces.size()) : nv;
    if (field->values.size() != expected)
      throw InputError("render: scalar '" + field->name + "' has " + std::to_string(field->values.size()) +
                       " values for " + std::to_string(expected) + (field->per_face ? " faces" : " vertices"));
  }

  const Camera cam = make_camera(options.view_direction, options.up);
  const int s = options.supersampling;
  const bool legend = options.legend && field && scale.has_value();
  const int plot_width = legend ? options.width * 4 / 5 : options.width;
  RenderSamples out;
  out.width = plot_width * s;
  out.height = options.height * s;
  const int W = out.width, H = out.height;  // supersampled plot area

  // Screen coordinates of the vertices, fitted into the plot area with a margin.
  Eigen::MatrixX3d screen(nv, 3);
  screen.col(0) = mesh.positions * cam.right;
  screen.col(1) = mesh.positions * cam.up;
  screen.col(2) = mesh.positions * cam.toward;
  const double extent_x = std::max(extent.hi_x - extent.lo_x, 1e-300),
               extent_y = std::max(extent.hi_y - extent.lo_y, 1e-300);
  const double zoom = 0.92 * std::min(double(W) / extent_x, double(H) / extent_y);
  const double mid_x = 0.5 * (extent.lo_x + extent.hi_x), mid_y = 0.5 * (extent.lo_y + extent.hi_y);
  for (Eigen::Index v = 0; v < nv; ++v) {
    screen(v, 0) = 0.5 * W + (screen(v, 0) - mid_x) * zoom;
    screen(v, 1) = 0.5 * H - (screen(v, 1) - mid_y) * zoom;  // rows grow downwards
  }

  // A key light from the upper left in front, and a fill light from the viewer so that faces turned
  // away from the key stay readable; the face normal is turned towards the viewer.
  // (For the default view the three axis directions of a staircase get shades 0.36, 0.56, 0.82.)
  const Eigen::Vector3d light = (cam.toward + 1.2 * cam.up - 0.3 * cam.right).normalized();
  const Eigen::Vector3d grey(0.78, 0.78, 0.78);
  const std::size_t n = std::size_t(W) * std::size_t(H);
  out.depth.assign(n, -std::numeric_limits<double>::infinity());
  out.face.assign(n, RenderSamples::kNoFace);
  out.colour.assign(3 * n, 1.0f);  // white background

  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const std::span<const int> face = mesh.faces[f];
    const std::int64_t id = face_ids.empty() ? std::int64_t(f) : face_ids[f];
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // Newell's normal of the polygon
    for (std::size_t k = 0; k < face.size(); ++k) {
      const Eigen::Vector3d a = mesh.positions.row(face[k]), b = mesh.positions.row(face[(k + 1) % face.size()]);
      normal += (a - b).cross(a + b);
    }
    const double length = normal.norm();
    normal = length > 0.0 ? Eigen::Vector3d(normal / length) : cam.toward;
    if (normal.dot(cam.toward) < 0.0) normal = -normal;
    const double shade = 0.2 + 0.5 * std::max(0.0, normal.dot(light)) + 0.3 * normal.dot(cam.toward);
    const double face_t =
        field && field->per_face ? (field->values[Eigen::Index(f)] - scale->min) / (scale->max - scale->min) : 0.0;
    for (std::size_t k = 1; k + 1 < face.size(); ++k) {  // fan from the first corner
      const int ids[3] = {face[0], face[k], face[k + 1]};
      const double x0 = screen(ids[0], 0), y0 = screen(ids[0], 1), x1 = screen(ids[1], 0), y1 = screen(ids[1], 1),
                   x2 = screen(ids[2], 0), y2 = screen(ids[2], 1);
      const double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
      if (area == 0.0) continue;  // seen edge-on
      const int px_lo = std::max(0, int(std::floor(std::min({x0, x1, x2})))),
                px_hi = std::min(W - 1, int(std::ceil(std::max({x0, x1, x2})))),
                py_lo = std::max(0, int(std::floor(std::min({y0, y1, y2})))),
                py_hi = std::min(H - 1, int(std::ceil(std::max({y0, y1, y2}))));
      double t[3] = {face_t, face_t, face_t};
      if (field && !field->per_face)
        for (int c = 0; c < 3; ++c) t[c] = (field->values[ids[c]] - scale->min) / (scale->max - scale->min);
      for (int py = py_lo; py <= py_hi; ++py)
        for (int px = px_lo; px <= px_hi; ++px) {
          const double x = px + 0.5, y = py + 0.5;
          // Barycentric coordinates; inside when all have the sign of the area.
          const double b1 = ((x - x0) * (y2 - y0) - (x2 - x0) * (y - y0)) / area;
          const double b2 = ((x1 - x0) * (y - y0) - (x - x0) * (y1 - y0)) / area;
          const double b0 = 1.0 - b1 - b2;
          if (b0 < 0.0 || b1 < 0.0 || b2 < 0.0) continue;
          const double z = b0 * screen(ids[0], 2) + b1 * screen(ids[1], 2) + b2 * screen(ids[2], 2);
          const std::size_t at = std::size_t(py) * std::size_t(W) + std::size_t(px);
          // Ties keep the lower face id (the first face drawn here): the same picture in any order of
          // equal depths, and when pieces drawn apart are merged.
          if (!(z > out.depth[at]) && !(z == out.depth[at] && id < out.face[at])) continue;
          out.depth[at] = z;
          out.face[at] = id;
          const Eigen::Vector3d base = field ? colormap_rgb(scale->map, b0 * t[0] + b1 * t[1] + b2 * t[2]) : grey;
          for (int c = 0; c < 3; ++c) out.colour[3 * at + std::size_t(c)] = float(shade * base[c]);
        }
    }
  }
  return out;
}

void merge_samples(RenderSamples& into, const RenderSamples& other, std::size_t first, std::size_t count) {
  if (into.width != other.width || into.height != other.height)
    throw InputError("render: samples of different sizes cannot be merged");
  const std::size_t n = std::size_t(into.width) * std::size_t(into.height);
  if (first > n || count > n - first) throw InputError("render: samples to merge beyond the picture");
  for (std::size_t at = first; at < first + count; ++at) {
    const double z = other.depth[at];
    if (!(z > into.depth[at]) && !(z == into.depth[at] && other.face[at] < into.face[at])) continue;
    into.depth[at] = z;
    into.face[at] = other.face[at];
    for (int c = 0; c < 3; ++c) into.colour[3 * at + std::size_t(c)] = other.colour[3 * at + std::size_t(c)];
  }
}

Image render_picture(const RenderSamples& samples, const std::optional<ColourScale>& scale, const std::string& name,
                     const RenderOptions& options) {
  check_render_options(options);
  const int s = options.supersampling;
  const bool legend = options.legend && scale.has_value();
  const int plot_width = legend ? options.width * 4 / 5 : options.width;
  const int W = plot_width * s;
  if (samples.width != W || samples.height != options.height * s ||
      samples.colour.size() != 3 * std::size_t(W) * std::size_t(samples.height))
    throw InputError("render: the samples do not match the picture's size");
  // Box filter of the s x s samples of each pixel.
  Image image(options.width, options.height);
  for (int y = 0; y < options.height; ++y)
    for (int x = 0; x < plot_width; ++x) {
      double sum[3] = {0, 0, 0};
      for (int dy = 0; dy < s; ++dy)
        for (int dx = 0; dx < s; ++dx) {
          const std::size_t at = std::size_t(y * s + dy) * std::size_t(W) + std::size_t(x * s + dx);
          for (int c = 0; c < 3; ++c) sum[c] += samples.colour[3 * at + std::size_t(c)];
        }
      std::uint8_t* p = image.pixel(x, y);
      for (int c = 0; c < 3; ++c) p[c] = to_byte(sum[c] / double(s * s));
    }
  if (legend) draw_legend(image, plot_width, *scale, name);
  return image;
}

Image render_mesh(const PolygonMesh& mesh, const ScalarField* field, const RenderOptions& options) {
  check_render_options(options);
  if (mesh.positions.rows() == 0) throw InputError("render: the mesh has no vertex");
  if (mesh.faces.empty()) throw InputError("render: the mesh has no face");
  if (!mesh.positions.allFinite()) throw InputError("render: the mesh has a non-finite vertex position");
  std::optional<ColourScale> scale;
  if (field) {
    const Eigen::Index expected = field->per_face ? Eigen::Index(mesh.faces.size()) : mesh.positions.rows();
    if (field->values.size() != expected)
      throw InputError("render: scalar '" + field->name + "' has " + std::to_string(field->values.size()) +
                       " values for " + std::to_string(expected) + (field->per_face ? " faces" : " vertices"));
    scale = colour_scale(*field, options);
  }
  const RenderSamples samples = render_samples(mesh, field, scale, screen_extent(mesh.positions, options), options);
  return render_picture(samples, scale, field ? field->name : std::string(), options);
}

}  // namespace corrlap

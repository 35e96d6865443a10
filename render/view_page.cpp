#include "view_page.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#if defined(CORRLAP_HAVE_ZLIB)
#include <zlib.h>
#endif

#if defined(CORRLAP_HAVE_VIEWER)
namespace corrlap::detail {
extern const unsigned char viewer_script[];  // <build>/viewer/viewer_script.cpp
extern const std::size_t viewer_script_size;
}  // namespace corrlap::detail
#endif

namespace corrlap {

namespace {

using Json = nlohmann::json;

std::string_view script() {
#if defined(CORRLAP_HAVE_VIEWER)
  return {reinterpret_cast<const char*>(detail::viewer_script), detail::viewer_script_size};
#else
  return {};
#endif
}

// The decoded buffer of viewer/README.md: arrays back to back at offsets that are multiples of 4,
// each filtered so that zlib finds the repeats (the byte planes of floats and of id differences
// are far more regular than the interleaved bytes).
class Buffer {
 public:
  Json add_float32(const std::vector<float>& values) {
    std::vector<std::uint32_t> bits(values.size());
    std::memcpy(bits.data(), values.data(), values.size() * 4);
    return add_words(bits, "float32", "shuffle");
  }
  Json add_uint32_deltas(const std::vector<std::uint32_t>& values) {
    std::vector<std::uint32_t> deltas(values.size());
    std::uint32_t before = 0;
    for (std::size_t i = 0; i < values.size(); ++i) {
      deltas[i] = values[i] - before;  // modulo 2^32, as the page adds them back
      before = values[i];
    }
    return add_words(deltas, "uint32", "delta+shuffle");
  }
  Json add_uint8(const std::vector<std::uint8_t>& values) {
    Json a = describe(values.size(), "uint8", "none");
    bytes_.insert(bytes_.end(), values.begin(), values.end());
    bytes_.resize((bytes_.size() + 3) / 4 * 4, 0);
    return a;
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  Json describe(std::size_t count, const char* type, const char* filter) const {
    return Json{{"offset", bytes_.size()}, {"count", count}, {"type", type}, {"filter", filter}};
  }
  // Byte plane k holds byte k (little-endian, least significant first) of every word.
  Json add_words(const std::vector<std::uint32_t>& words, const char* type, const char* filter) {
    Json a = describe(words.size(), type, filter);
    const std::size_t n = words.size(), at = bytes_.size();
    bytes_.resize(at + 4 * n);
    for (int k = 0; k < 4; ++k) {
      std::uint8_t* plane = bytes_.data() + at + std::size_t(k) * n;
      for (std::size_t i = 0; i < n; ++i) plane[i] = std::uint8_t(words[i] >> (8 * k));
    }
    return a;
  }
  std::vector<std::uint8_t> bytes_;
};

bool is_float(double x) { return std::isfinite(x) && std::abs(x) <= double(std::numeric_limits<float>::max()); }

// Checked before anything is encoded, so that a bad surface fails with its name and nothing
// half-built.
void check_surface(const ViewSurface& s) {
  const std::string name = "surface '" + s.name + "'";
  const Eigen::Index nv = s.mesh.positions.rows();
  if (nv == 0 || s.mesh.faces.empty()) throw InputError("view: " + name + " is empty");
  if (std::uint64_t(nv) > std::numeric_limits<std::uint32_t>::max())
    throw InputError("view: " + name + " has more than 2^32 vertices");
  // The message is built for the first bad coordinate only: nothing is allocated per vertex.
  for (Eigen::Index v = 0; v < nv; ++v)
    for (int c = 0; c < 3; ++c)
      if (!is_float(s.mesh.positions(v, c)))
        throw InputError("view: " + name + ", vertex " + std::to_string(v) + " is " +
                         std::to_string(s.mesh.positions(v, c)) + ", not a finite float");
  for (std::size_t f = 0; f < s.mesh.faces.size(); ++f) {
    const auto face = s.mesh.faces[f];
    if (face.size() < 3 || face.size() > 255)
      throw InputError("view: " + name + ", face " + std::to_string(f) + " has " + std::to_string(face.size()) +
                       " corners (3 to 255 are drawn)");
    for (int v : face)
      if (v < 0 || v >= nv)
        throw InputError("view: " + name + ", face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                         " of " + std::to_string(nv));
  }
  std::set<std::string> names;
  for (const ScalarField& field : s.fields) {
    const Eigen::Index expected = field.per_face ? Eigen::Index(s.mesh.faces.size()) : nv;
    if (field.values.size() != expected)
      throw InputError("view: " + name + ", field '" + field.name + "' has " + std::to_string(field.values.size()) +
                       " values for " + std::to_string(expected) + (field.per_face ? " faces" : " vertices"));
    if (!names.insert(field.name).second)
      throw InputError("view: " + name + " has two fields named '" + field.name + "'");
  }
}

// One range for every surface's field of a name: colour_scale of their finite values together.
ColourScale common_scale(const std::vector<ViewSurface>& surfaces, const std::string& name) {
  ScalarField all{name, {}, false};
  std::vector<double> finite;
  for (const ViewSurface& s : surfaces)
    for (const ScalarField& f : s.fields)
      if (f.name == name)
        for (double x : f.values)
          if (std::isfinite(x)) finite.push_back(x);
  if (finite.empty()) return ColourScale{};  // nothing to colour: every value is drawn as undefined
  all.values = Eigen::Map<const Eigen::VectorXd>(finite.data(), Eigen::Index(finite.size()));
  return colour_scale(all, RenderOptions{});
}

Json colormap_stops(Colormap map) {
  Json stops = Json::array();
  for (int i = 0; i <= 4; ++i) {
    const Eigen::Vector3d c = colormap_rgb(map, i / 4.0);
    stops.push_back({c.x(), c.y(), c.z()});
  }
  return stops;
}

Json encode_surface(const ViewSurface& s, Buffer& buffer) {
  Json m{
      {"name", s.name}, {"vertices", s.mesh.positions.rows()}, {"faces", s.mesh.faces.size()}, {"visible", s.visible}};
  std::vector<float> positions(std::size_t(s.mesh.positions.rows()) * 3);
  for (Eigen::Index v = 0; v < s.mesh.positions.rows(); ++v)
    for (int c = 0; c < 3; ++c) positions[std::size_t(v) * 3 + std::size_t(c)] = float(s.mesh.positions(v, c));
  m["positions"] = buffer.add_float32(positions);

  std::vector<std::uint32_t> corners;
  corners.reserve(s.mesh.faces.num_corners());
  std::vector<std::uint8_t> sizes;
  sizes.reserve(s.mesh.faces.size());
  for (const auto face : s.mesh.faces) {
    sizes.push_back(std::uint8_t(face.size()));
    for (int v : face) corners.push_back(std::uint32_t(v));
  }
  const bool uniform = std::all_of(sizes.begin(), sizes.end(), [&](std::uint8_t k) { return k == sizes.front(); });
  m["face_size"] = uniform ? int(sizes.front()) : 0;
  m["face_sizes"] = uniform ? Json(nullptr) : buffer.add_uint8(sizes);
  m["corners"] = buffer.add_uint32_deltas(corners);

  Json vertex_fields = Json::object(), face_fields = Json::object();
  for (const ScalarField& field : s.fields) {
    std::vector<float> values(std::size_t(field.values.size()));
    for (Eigen::Index i = 0; i < field.values.size(); ++i) {
      const double x = field.values[i];
      // NaN stays NaN (undefined, drawn grey); an infinite or huge value is clamped to float's range.
      values[std::size_t(i)] = std::isnan(x) ? std::numeric_limits<float>::quiet_NaN()
                                             : float(std::clamp(x, -double(std::numeric_limits<float>::max()),
                                                                double(std::numeric_limits<float>::max())));
    }
    (field.per_face ? face_fields : vertex_fields)[field.name] = buffer.add_float32(values);
  }
  m["vertex_fields"] = vertex_fields;
  m["face_fields"] = face_fields;
  return m;
}

std::string base64(const std::uint8_t* data, std::size_t n) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= n; i += 3) {
    const std::uint32_t w = std::uint32_t(data[i]) << 16 | std::uint32_t(data[i + 1]) << 8 | data[i + 2];
    for (int k = 18; k >= 0; k -= 6) out.push_back(kDigits[(w >> k) & 63]);
  }
  if (i < n) {
    const std::uint32_t w = std::uint32_t(data[i]) << 16 | (i + 1 < n ? std::uint32_t(data[i + 1]) << 8 : 0u);
    out.push_back(kDigits[(w >> 18) & 63]);
    out.push_back(kDigits[(w >> 12) & 63]);
    out.push_back(i + 1 < n ? kDigits[(w >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

// The buffer as the page's DATA, and its encoding's name.
std::pair<std::string, std::string> encode_data(const std::vector<std::uint8_t>& bytes, bool compress) {
#if defined(CORRLAP_HAVE_ZLIB)
  if (compress) {
    uLongf size = compressBound(uLong(bytes.size()));
    std::vector<std::uint8_t> packed(size);
    // Level 1: the page is written by default beside every regularization, whose time matters more
    // than a few percent of the page's size (bench/RESULTS.md, "The viewer's pages").
    if (compress2(packed.data(), &size, bytes.data(), uLong(bytes.size()), 1) != Z_OK)
      throw Error("view: zlib could not compress the geometry");
    return {base64(packed.data(), size), "deflate+base64"};
  }
#else
  (void)compress;
#endif
  return {base64(bytes.data(), bytes.size()), "base64"};
}

std::string initial_field(const std::string& wanted, const std::vector<std::string>& names) {
  if (wanted == "none") return {};
  if (wanted == "auto") {
    if (std::find(names.begin(), names.end(), "H") != names.end()) return "H";
    return names.empty() ? std::string() : names.front();
  }
  if (std::find(names.begin(), names.end(), wanted) == names.end()) {
    std::string have;
    for (const std::string& n : names) have += " " + n;
    throw InputError("view: no surface has a field '" + wanted + "'" +
                     (have.empty() ? std::string(" (they have none)") : "; the fields are:" + have));
  }
  return wanted;
}

}  // namespace

bool has_viewer() { return !script().empty(); }

void check_viewer() {
  if (!has_viewer())
    throw Error(
        "view: this build of corrlap has no viewer (it was built without node and npm: install them, e.g. "
        "scripts/install_deps.sh, and build again)");
}

std::string view_page(const std::vector<ViewSurface>& surfaces, const ViewOptions& options) {
  check_viewer();
  if (surfaces.empty()) throw InputError("view: no surface to show");
  for (const ViewSurface& s : surfaces) check_surface(s);
  if (options.layout != "overlay" && options.layout != "side")
    throw InputError("view: layout '" + options.layout + "': expected overlay or side");
  if (!options.view_direction.allFinite() || options.view_direction.norm() == 0.0 || !options.up.allFinite() ||
      options.up.norm() == 0.0)
    throw InputError("view: the view and up directions must be finite nonzero vectors");
  // Refused before the buffer is allocated: zlib shrinks the geometry about 2 to 3 times and base64
  // grows it by a third, so 8 times the limit cannot fit.
  std::uint64_t raw = 0;
  for (const ViewSurface& s : surfaces) {
    raw += std::uint64_t(s.mesh.positions.rows()) * 12 + s.mesh.faces.num_corners() * 4 + s.mesh.faces.size();
    for (const ScalarField& f : s.fields) raw += std::uint64_t(f.values.size()) * 4;
  }
  if (raw > 8 * std::uint64_t(options.max_encoded_bytes))
    throw InputError("view: the surfaces have " + std::to_string(raw) +
                     " bytes of geometry, too large for a browser page (at most " +
                     std::to_string(options.max_encoded_bytes) + " once encoded); show fewer or coarser surfaces");

  std::vector<std::string> names;  // in the order of first appearance
  for (const ViewSurface& s : surfaces)
    for (const ScalarField& f : s.fields)
      if (std::find(names.begin(), names.end(), f.name) == names.end()) names.push_back(f.name);
  const std::string first = initial_field(options.initial_field, names);

  Buffer buffer;
  Json meshes = Json::array();
  for (const ViewSurface& s : surfaces) meshes.push_back(encode_surface(s, buffer));
  Json fields = Json::array();
  for (const std::string& n : names) {
    const auto given = options.scales.find(n);
    const ColourScale scale = given != options.scales.end() ? given->second : common_scale(surfaces, n);
    if (!std::isfinite(scale.min) || !std::isfinite(scale.max) || !(scale.max > scale.min))
      throw InputError("view: the colour range of '" + n + "' is empty (need finite min < max)");
    fields.push_back({{"name", n}, {"min", scale.min}, {"max", scale.max}, {"colormap", to_string(scale.map)}});
  }
  auto [data, encoding] = encode_data(buffer.bytes(), options.compress);
  if (data.size() > options.max_encoded_bytes)
    throw InputError("view: the geometry is " + std::to_string(data.size()) +
                     " bytes once encoded, too large for a browser page (at most " +
                     std::to_string(options.max_encoded_bytes) + "); show fewer or coarser surfaces");

  const Eigen::Vector3d d = options.view_direction.normalized(), u = options.up.normalized();
  const Json scene{
      {"format", "corrlap-view 1"},
      {"title", options.title},
      {"data", {{"encoding", encoding}, {"bytes", buffer.bytes().size()}}},
      {"view", {{"direction", {d.x(), d.y(), d.z()}}, {"up", {u.x(), u.y(), u.z()}}}},
      {"colormaps",
       {{"sequential", colormap_stops(Colormap::Sequential)}, {"diverging", colormap_stops(Colormap::Diverging)}}},
      {"fields", fields},
      {"initial_field", first.empty() ? Json(nullptr) : Json(first)},
      {"layout", options.layout},
      {"meshes", meshes}};
  // Invalid UTF-8 in a name (a file name) becomes U+FFFD rather than an error. '<' only occurs
  // inside JSON strings, where \u003c means the same and cannot close the <script> element.
  std::string scene_text = scene.dump(-1, ' ', false, Json::error_handler_t::replace);
  std::string escaped;
  escaped.reserve(scene_text.size());
  for (char c : scene_text) escaped += c == '<' ? std::string("\\u003c") : std::string(1, c);

  std::string title_html;  // the title as HTML text
  for (char c : options.title) {
    if (c == '<')
      title_html += "&lt;";
    else if (c == '&')
      title_html += "&amp;";
    else
      title_html += c;
  }
  const std::string_view js = script();
  std::string page;
  page.reserve(data.size() + js.size() + escaped.size() + 512);
  page += "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>" + title_html + "</title></head><body>\n";
  page += "<script type=\"application/json\" id=\"corrlap-scene\">" + escaped + "</script>\n";
  page += "<script type=\"application/octet-stream\" id=\"corrlap-data\">";
  page += data;
  page += "</script>\n<script>";
  page += js;
  page += "</script>\n</body></html>\n";
  return page;
}

void write_view_page(const std::string& path, const std::vector<ViewSurface>& surfaces, const ViewOptions& options) {
  const std::string page = view_page(surfaces, options);
  const std::string partial = path + ".partial";
  std::FILE* f = std::fopen(partial.c_str(), "wb");
  if (!f) throw IoError(path + ": cannot write the page (" + std::strerror(errno) + ")");
  const bool written = std::fwrite(page.data(), 1, page.size(), f) == page.size();
  const bool closed = std::fclose(f) == 0;
  std::error_code ec;
  if (!written || !closed) {
    std::filesystem::remove(partial, ec);
    throw IoError(path + ": cannot write the page (disk full?)");
  }
  std::filesystem::rename(partial, path, ec);
  if (ec) {
    std::filesystem::remove(partial, ec);
    throw IoError(path + ": cannot write the page (" + ec.message() + ")");
  }
}

}  // namespace corrlap

// view_page: the page holds the surfaces exactly as the format of viewer/README.md says (decoded
// here independently of the page's script), the colour maps and ranges of the PNG pictures, an
// escaped scene, and names what it refuses. The page in a browser: tests/viewer/browser_test.mjs.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/render/view_page.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

using namespace corrlap;
using Json = nlohmann::json;

namespace {

// A triangle and a quad sharing an edge, and a pentagon apart: faces of three sizes.
ViewSurface mixed_surface() {
  ViewSurface s;
  s.name = "mixed <&> surface";
  s.mesh.positions.resize(9, 3);
  s.mesh.positions << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, -1, 0, 3, 0, 1, 4, 0, 1, 4.5, 1, 1, 3.5, 2, 1;
  s.mesh.faces = {{0, 4, 1}, {0, 1, 2, 3}, {5, 6, 7, 8, 2}};
  s.fields.push_back({"H", Eigen::VectorXd::LinSpaced(9, -2.0, 6.0), false});
  Eigen::VectorXd area(3);
  area << 0.5, std::nan(""), 2.0;
  s.fields.push_back({"area", area, true});
  return s;
}

// A unit cube of quads.
ViewSurface cube(const std::string& name) {
  ViewSurface s;
  s.name = name;
  s.mesh.positions.resize(8, 3);
  for (int v = 0; v < 8; ++v) s.mesh.positions.row(v) << (v & 1), (v >> 1) & 1, (v >> 2) & 1;
  s.mesh.faces = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  Eigen::VectorXd h(8);
  h << 1, 2, 3, 4, 5, 6, 7, 8;
  s.fields.push_back({"H", h, false});
  return s;
}

std::string between(const std::string& text, const std::string& open, const std::string& close) {
  const std::size_t a = text.find(open);
  REQUIRE(a != std::string::npos);
  const std::size_t b = text.find(close, a + open.size());
  REQUIRE(b != std::string::npos);
  return text.substr(a + open.size(), b - a - open.size());
}

std::vector<std::uint8_t> from_base64(const std::string& text) {
  std::vector<std::uint8_t> out;
  std::uint32_t acc = 0;
  int bits = 0;
  bool valid = true;
  for (char c : text) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    if (c >= '0' && c <= '9') v = c - '0' + 52;
    if (c == '+') v = 62;
    if (c == '/') v = 63;
    if (c == '=') break;
    valid = valid && v >= 0;
    acc = acc << 6 | std::uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(std::uint8_t(acc >> bits));
    }
  }
  CHECK(valid);
  return out;
}

struct Page {
  Json scene;
  std::vector<std::uint8_t> data;  // decoded, uncompressed pages only
};

Page parse(const std::string& html) {
  Page p;
  const std::string scene = between(html, "<script type=\"application/json\" id=\"corrlap-scene\">", "</script>");
  CHECK(scene.find('<') == std::string::npos);
  p.scene = Json::parse(scene);
  const std::string data = between(html, "<script type=\"application/octet-stream\" id=\"corrlap-data\">", "</script>");
  if (p.scene["data"]["encoding"] == "base64") {
    p.data = from_base64(data);
    CHECK(p.data.size() == p.scene["data"]["bytes"].get<std::size_t>());
  }
  return p;
}

// The elements of ARRAY `a` as 32-bit words (un-shuffled, deltas summed) or bytes.
std::vector<std::uint32_t> words(const Page& p, const Json& a) {
  const std::size_t offset = a["offset"], count = a["count"];
  CHECK(offset % 4 == 0);
  std::vector<std::uint32_t> out(count);
  if (a["type"] == "uint8") {
    CHECK(a["filter"] == "none");
    for (std::size_t i = 0; i < count; ++i) out[i] = p.data.at(offset + i);
    return out;
  }
  REQUIRE(offset + 4 * count <= p.data.size());
  for (std::size_t i = 0; i < count; ++i)
    for (int k = 0; k < 4; ++k) out[i] |= std::uint32_t(p.data[offset + std::size_t(k) * count + i]) << (8 * k);
  if (a["filter"] == "delta+shuffle")
    for (std::size_t i = 1; i < count; ++i) out[i] += out[i - 1];
  else
    CHECK(a["filter"] == "shuffle");
  return out;
}

std::vector<float> floats(const Page& p, const Json& a) {
  CHECK(a["type"] == "float32");
  const std::vector<std::uint32_t> w = words(p, a);
  std::vector<float> out(w.size());
  std::memcpy(out.data(), w.data(), 4 * w.size());
  return out;
}

}  // namespace

TEST_CASE("view_page: positions, faces of any size and both kinds of fields decode to the surface's values") {
  if (!has_viewer()) {
    CHECK_THROWS_AS(view_page({cube("c")}), Error);
    MESSAGE("skipped: this build has no viewer");
    return;
  }
  const ViewSurface s = mixed_surface();
  ViewOptions o;
  o.compress = false;
  o.title = "a <title>";
  const std::string html = view_page({s, cube("cube")}, o);
  CHECK(html.find("<title>a &lt;title></title>") != std::string::npos);
  const Page p = parse(html);
  CHECK(p.scene["format"] == "corrlap-view 1");
  CHECK(p.scene["title"] == "a <title>");  // escaped in the text only
  REQUIRE(p.scene["meshes"].size() == 2);
  const Json& m = p.scene["meshes"][0];
  CHECK(m["name"] == s.name);
  CHECK(m["vertices"] == 9);
  CHECK(m["faces"] == 3);
  const std::vector<float> positions = floats(p, m["positions"]);
  REQUIRE(positions.size() == 27);
  for (int v = 0; v < 9; ++v)
    for (int c = 0; c < 3; ++c) CHECK(positions[std::size_t(3 * v + c)] == float(s.mesh.positions(v, c)));
  // Mixed sizes: face_size 0 and one size per face.
  CHECK(m["face_size"] == 0);
  const std::vector<std::uint32_t> sizes = words(p, m["face_sizes"]);
  CHECK(sizes == std::vector<std::uint32_t>{3, 4, 5});
  const std::vector<std::uint32_t> corners = words(p, m["corners"]);
  CHECK(corners == std::vector<std::uint32_t>{0, 4, 1, 0, 1, 2, 3, 5, 6, 7, 8, 2});  // 8 -> 2: a negative delta
  const std::vector<float> h = floats(p, m["vertex_fields"]["H"]);
  for (int v = 0; v < 9; ++v) CHECK(h[std::size_t(v)] == float(s.fields[0].values[v]));
  const std::vector<float> area = floats(p, m["face_fields"]["area"]);
  CHECK(area[0] == 0.5f);
  CHECK(std::isnan(area[1]));  // undefined stays undefined
  CHECK(area[2] == 2.0f);
  // The cube: all quads.
  const Json& c = p.scene["meshes"][1];
  CHECK(c["face_size"] == 4);
  CHECK(c["face_sizes"].is_null());
  CHECK(words(p, c["corners"]).size() == 24);
  CHECK(c["visible"] == true);
}

TEST_CASE("view_page: the colour maps and the common range are the PNG renderer's") {
  if (!has_viewer()) return;
  ViewOptions o;
  o.compress = false;
  const ViewSurface a = mixed_surface(), b = cube("cube");
  const Page p = parse(view_page({a, b}, o));
  for (const auto& [name, map] : {std::pair{"sequential", Colormap::Sequential}, {"diverging", Colormap::Diverging}}) {
    const Json& stops = p.scene["colormaps"][name];
    REQUIRE(stops.size() == 5);
    for (int i = 0; i < 5; ++i)
      for (int k = 0; k < 3; ++k)
        CHECK(stops[std::size_t(i)][std::size_t(k)].get<double>() == colormap_rgb(map, i / 4.0)[k]);
  }
  // H on both surfaces: one range, that of their values together, as colour_scale computes it.
  Eigen::VectorXd all(17);
  all << a.fields[0].values, b.fields[0].values;
  const ColourScale expected = colour_scale(ScalarField{"H", all, false}, RenderOptions{});
  const Json& fields = p.scene["fields"];
  REQUIRE(fields.size() == 2);
  CHECK(fields[0]["name"] == "H");
  CHECK(fields[0]["min"].get<double>() == expected.min);
  CHECK(fields[0]["max"].get<double>() == expected.max);
  CHECK(fields[0]["colormap"] == to_string(expected.map));
  // area: its NaN left out.
  Eigen::VectorXd area(2);
  area << 0.5, 2.0;
  CHECK(fields[1]["min"].get<double>() == colour_scale(ScalarField{"area", area, true}, RenderOptions{}).min);
  CHECK(p.scene["initial_field"] == "H");  // auto
  CHECK(p.scene["layout"] == "side");
  // A given scale wins; another initial field and layout.
  o.scales["H"] = ColourScale{-1.0, 3.0, Colormap::Diverging};
  o.initial_field = "area";
  o.layout = "overlay";
  const Page q = parse(view_page({a, b}, o));
  CHECK(q.scene["fields"][0]["min"] == -1.0);
  CHECK(q.scene["fields"][0]["max"] == 3.0);
  CHECK(q.scene["initial_field"] == "area");
  CHECK(q.scene["layout"] == "overlay");
  o.initial_field = "none";
  CHECK(parse(view_page({a}, o)).scene["initial_field"].is_null());
}

TEST_CASE("view_page: compressed pages carry the same scene and are smaller, write_view_page writes the page") {
  if (!has_viewer()) return;
  ViewSurface big = cube("cube");
  // A finer surface so that compression has something to work on: a 60 x 60 grid of quads.
  big.mesh.positions.resize(61 * 61, 3);
  big.mesh.faces = {};
  for (int j = 0; j <= 60; ++j)
    for (int i = 0; i <= 60; ++i) big.mesh.positions.row(j * 61 + i) << i * 0.1, j * 0.1, std::sin(i * 0.1);
  for (int j = 0; j < 60; ++j)
    for (int i = 0; i < 60; ++i)
      big.mesh.faces.push_back({j * 61 + i, j * 61 + i + 1, (j + 1) * 61 + i + 1, (j + 1) * 61 + i});
  big.fields = {{"H", big.mesh.positions.col(2), false}};
  ViewOptions plain;
  plain.compress = false;
  const std::string a = view_page({big}, plain), b = view_page({big});
  Page pa = parse(a), pb = parse(b);
  const bool zlib = pb.scene["data"]["encoding"] == "deflate+base64";
  if (zlib) CHECK(b.size() < a.size());
  pa.scene["data"].erase("encoding");
  pb.scene["data"].erase("encoding");
  CHECK(pa.scene == pb.scene);
  const std::string path = test::tmp_path("view_page_test.html");
  write_view_page(path, {big});
  std::ifstream in(path, std::ios::binary);
  const std::string written((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK(written == b);
  CHECK(!std::filesystem::exists(path + ".partial"));
  CHECK_THROWS_AS(write_view_page(test::tmp_path("no such folder/view.html"), {big}), IoError);
}

TEST_CASE("view_page: what it refuses is named") {
  if (!has_viewer()) return;
  const auto refuses = [](const std::vector<ViewSurface>& s, const std::string& words, ViewOptions o = {}) {
    CAPTURE(words);
    try {
      (void)view_page(s, o);
      FAIL("accepted");
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find(words) != std::string::npos);
    }
  };
  refuses({}, "no surface");
  ViewSurface s = cube("c");
  s.mesh.faces = {};
  refuses({s}, "surface 'c' is empty");
  s = cube("c");
  s.mesh.positions(3, 1) = std::nan("");
  refuses({s}, "vertex 3");
  s = cube("c");
  s.mesh.positions(2, 0) = 1e300;
  refuses({s}, "not a finite float");
  s = cube("c");
  s.mesh.faces.push_back({0, 9, 1});
  refuses({s}, "refers to vertex 9");
  s = cube("c");
  s.mesh.faces.push_back({0, 1});
  refuses({s}, "has 2 corners");
  s = cube("c");
  s.fields.push_back({"k", Eigen::VectorXd::Zero(7), false});
  refuses({s}, "field 'k' has 7 values for 8 vertices");
  s = cube("c");
  s.fields.push_back({"H", Eigen::VectorXd::Zero(8), false});
  refuses({s}, "two fields named 'H'");
  ViewOptions o;
  o.initial_field = "K";
  refuses({cube("c")}, "no surface has a field 'K'; the fields are: H", o);
  o = {};
  o.layout = "grid";
  refuses({cube("c")}, "layout 'grid'", o);
  o = {};
  o.scales["H"] = ColourScale{1.0, 1.0, Colormap::Sequential};
  refuses({cube("c")}, "colour range of 'H' is empty", o);
  o = {};
  o.max_encoded_bytes = 64;  // what a page too large for a browser gets: refused once encoded
  refuses({cube("c")}, "too large for a browser page (at most 64)", o);
  o.max_encoded_bytes = 8;  // or before, when the geometry is 8 times the limit (96 + 96 + 6 mesh bytes, 32 of H)
  refuses({cube("c")}, "the surfaces have 230 bytes of geometry, too large for a browser page (at most 8 once", o);
  o = {};
  o.view_direction = Eigen::Vector3d::Zero();
  refuses({cube("c")}, "view and up directions", o);
}

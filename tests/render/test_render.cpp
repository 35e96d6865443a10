// render_mesh: what is in front is drawn, colours follow the scalar and the colour bar, the same
// input gives the same bytes, PNG round trips, and bad input is named.
#include <doctest/doctest.h>

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/render/render_mesh.hpp>

#include "test_support.hpp"

using namespace corrlap;

namespace {

// Two unit squares facing +z, the first at z = `z_first`, the second at z = 0; face scalars 1, 0.
PolygonMesh two_squares(double z_first) {
  PolygonMesh m;
  m.positions.resize(8, 3);
  const double xy[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int k = 0; k < 4; ++k) {
    m.positions.row(k) << xy[k][0], xy[k][1], z_first;
    m.positions.row(4 + k) << xy[k][0], xy[k][1], 0.0;
  }
  m.faces = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  return m;
}

Eigen::Vector3i rgb_at(const Image& image, int x, int y) {
  const std::uint8_t* p = image.pixel(x, y);
  return {p[0], p[1], p[2]};
}

bool is_white(const Image& image, int x, int y) { return rgb_at(image, x, y) == Eigen::Vector3i(255, 255, 255); }

}  // namespace

TEST_CASE("render: the nearer face is drawn, whatever the face order, the same input gives the same bytes") {
  RenderOptions o;
  o.width = o.height = 64;
  o.view_direction = Eigen::Vector3d(0, 0, 1);  // looking down -z: larger z is nearer
  o.up = Eigen::Vector3d(0, 1, 0);
  o.legend = false;
  o.range_min = 0.0;
  o.range_max = 1.0;
  o.colormap = Colormap::Sequential;
  ScalarField field{"s", Eigen::Vector2d(1.0, 0.0), true};
  const Image front_first = render_mesh(two_squares(0.5), &field, o);
  REQUIRE(front_first.width == 64);
  REQUIRE(front_first.rgb.size() == 64 * 64 * 3);
  // Facing the viewer: shade = 0.2 + 0.5 n.key + 0.3 n.view, times the colour at t = 1.
  const Eigen::Vector3d light =
      (Eigen::Vector3d(0, 0, 1) + 1.2 * Eigen::Vector3d(0, 1, 0) - 0.3 * Eigen::Vector3d(1, 0, 0)).normalized();
  const Eigen::Vector3d expected = (0.2 + 0.5 * light.z() + 0.3) * colormap_rgb(Colormap::Sequential, 1.0) * 255.0;
  const Eigen::Vector3i centre = rgb_at(front_first, 32, 32);
  for (int c = 0; c < 3; ++c) CHECK(std::abs(centre[c] - expected[c]) <= 1.0);
  // The back square (scalar 0) drawn first, the front one second: the same picture.
  PolygonMesh swapped = two_squares(0.5);
  std::swap_ranges(swapped.faces[0].begin(), swapped.faces[0].end(), swapped.faces[1].begin());  // two quads
  ScalarField swapped_field{"s", Eigen::Vector2d(0.0, 1.0), true};
  CHECK(render_mesh(swapped, &swapped_field, o).rgb == front_first.rgb);
  // Moving the first square behind the second shows the second's colour.
  const Image back = render_mesh(two_squares(-0.5), &field, o);
  const Eigen::Vector3d expected_back = (0.2 + 0.5 * light.z() + 0.3) * colormap_rgb(Colormap::Sequential, 0.0) * 255.0;
  for (int c = 0; c < 3; ++c) CHECK(std::abs(rgb_at(back, 32, 32)[c] - expected_back[c]) <= 1.0);
  // The squares fill 92% of the picture: the corners are background.
  CHECK(is_white(front_first, 0, 0));
  CHECK(is_white(front_first, 63, 63));
  CHECK(render_mesh(two_squares(0.5), &field, o).rgb == front_first.rgb);
}

TEST_CASE("render: a sphere coloured by height has the top colour at the top and a matching colour bar") {
  const PolygonMesh sphere = test::icosphere(4);
  ScalarField z{"z", sphere.positions.col(2), false};
  RenderOptions o;
  o.width = 200;
  o.height = 160;
  o.view_direction = Eigen::Vector3d(1, 0, 0);  // z up on the screen
  o.colormap = Colormap::Sequential;
  o.range_min = -1.0;
  o.range_max = 1.0;
  const Image image = render_mesh(sphere, &z, o);
  const int plot = 200 * 4 / 5;
  // Near the top of the disc the interpolated scalar is near 1, near the bottom near -1: the
  // pixels' hue follows the map (compare the ratio of blue to green, independent of the shade).
  const Eigen::Vector3i top = rgb_at(image, plot / 2, 80 - 60), bottom = rgb_at(image, plot / 2, 80 + 60);
  const Eigen::Vector3d top_map = colormap_rgb(Colormap::Sequential, 0.9),
                        bottom_map = colormap_rgb(Colormap::Sequential, 0.1);
  CHECK(top[0] > top[2]);          // yellow-green: more red than blue
  CHECK(bottom[2] > bottom[0]);    // violet-blue: more blue than red
  CHECK(top_map[0] > top_map[2]);  // (the map itself, for the reader)
  CHECK(bottom_map[2] > bottom_map[0]);
  // The colour bar: the maximum colour at its top, the minimum at its bottom, unshaded.
  bool found_top = false, found_bottom = false;
  const Eigen::Vector3d cmax = colormap_rgb(Colormap::Sequential, 1.0) * 255.0,
                        cmin = colormap_rgb(Colormap::Sequential, 0.0) * 255.0;
  for (int x = plot; x < 200; ++x) {
    const Eigen::Vector3d at_top = rgb_at(image, x, 160 / 6).cast<double>(),
                          at_bottom = rgb_at(image, x, 160 - 160 / 6).cast<double>();
    found_top = found_top || (at_top - cmax).cwiseAbs().maxCoeff() <= 1.0;
    found_bottom = found_bottom || (at_bottom - cmin).cwiseAbs().maxCoeff() <= 1.0;
  }
  CHECK(found_top);
  CHECK(found_bottom);
  // Background left and right of the disc in the plot area.
  CHECK(is_white(image, 1, 80));
  CHECK(!is_white(image, plot / 2, 80));
}

TEST_CASE("render: automatic colour scales") {
  RenderOptions o;
  Eigen::VectorXd signed_values = Eigen::VectorXd::LinSpaced(101, -2.0, 1.0);
  const ColourScale s = colour_scale({"H", signed_values, false}, o);
  CHECK(s.map == Colormap::Diverging);
  CHECK(s.max == doctest::Approx(-s.min));
  CHECK(s.max == doctest::Approx(1.94));  // the 98th percentile of |v|: the third largest of 101, 2 - 2 * 0.03
  Eigen::VectorXd positive = Eigen::VectorXd::LinSpaced(101, 0.0, 100.0);
  const ColourScale p = colour_scale({"d", positive, false}, o);
  CHECK(p.map == Colormap::Sequential);
  CHECK(p.min == doctest::Approx(2.0));
  CHECK(p.max == doctest::Approx(98.0));
  const ColourScale constant = colour_scale({"c", Eigen::VectorXd::Constant(5, 3.0), false}, o);
  CHECK(constant.min < 3.0);
  CHECK(constant.max > 3.0);
}

TEST_CASE("render: PNG round trip and unreadable files") {
  RenderOptions o;
  o.width = 48;
  o.height = 32;
  const Image image = render_mesh(test::icosphere(2), nullptr, o);
  const std::string path = test::tmp_path("render_roundtrip.png");
  write_png(path, image);
  const Image back = read_png(path);
  CHECK(back.width == 48);
  CHECK(back.height == 32);
  CHECK(back.rgb == image.rgb);
  const std::string junk = test::tmp_path("render_junk.png");
  test::write_text(junk, "not a png at all");
  CHECK_THROWS_AS(read_png(junk), IoError);
  CHECK_THROWS_AS(read_png(test::tmp_path("no_such_dir/none.png")), IoError);
  CHECK_THROWS_AS(write_png(test::tmp_path("no_such_dir/out.png"), image), IoError);
}

TEST_CASE("render: bad input is named") {
  const PolygonMesh sphere = test::icosphere(1);
  RenderOptions o;
  const auto message = [&](const PolygonMesh& m, const ScalarField* f, const RenderOptions& opt) -> std::string {
    try {
      render_mesh(m, f, opt);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  CHECK(message(PolygonMesh{}, nullptr, o).find("no vertex") != std::string::npos);
  PolygonMesh no_faces = sphere;
  no_faces.faces.clear();
  CHECK(message(no_faces, nullptr, o).find("no face") != std::string::npos);
  PolygonMesh bad_index = sphere;
  bad_index.faces[3][1] = 999;
  CHECK(message(bad_index, nullptr, o).find("face 3 refers to vertex 999") != std::string::npos);
  PolygonMesh nan_position = sphere;
  nan_position.positions(2, 1) = std::nan("");
  CHECK(message(nan_position, nullptr, o).find("non-finite") != std::string::npos);
  ScalarField short_field{"H", Eigen::VectorXd::Zero(3), false};
  CHECK(message(sphere, &short_field, o).find("'H' has 3 values for 42 vertices") != std::string::npos);
  ScalarField nan_field{"H", Eigen::VectorXd::Zero(42), false};
  nan_field.values[7] = std::nan("");
  CHECK(message(sphere, &nan_field, o).find("not finite at vertex 7") != std::string::npos);
  RenderOptions zero_view = o;
  zero_view.view_direction.setZero();
  CHECK(message(sphere, nullptr, zero_view).find("view direction") != std::string::npos);
  RenderOptions huge = o;
  huge.width = 100000;
  CHECK(message(sphere, nullptr, huge).find("width 100000") != std::string::npos);
  RenderOptions too_many = o;
  too_many.width = too_many.height = 8192;
  too_many.supersampling = 4;
  CHECK(message(sphere, nullptr, too_many).find("more than 67 M") != std::string::npos);
  RenderOptions empty_range = o;
  empty_range.range_min = 1.0;
  empty_range.range_max = 1.0;
  ScalarField ok{"H", Eigen::VectorXd::Zero(42), false};
  CHECK(message(sphere, &ok, empty_range).find("empty") != std::string::npos);
  // Up along the view is not an error: another axis is drawn upwards.
  RenderOptions along = o;
  along.width = along.height = 32;
  along.view_direction = Eigen::Vector3d(0, 0, 1);
  CHECK(message(sphere, nullptr, along) == "no error");
}

#ifdef CORRLAP_CLI
TEST_CASE("corrlap render: a PLY scalar by name, clear errors for a missing one") {
  const PolygonMesh sphere = test::icosphere(3);
  MeshAttributes a;
  a.vertex_scalars["H"] = Eigen::VectorXd::Ones(sphere.positions.rows());
  a.vertex_scalars["height"] = sphere.positions.col(2);
  const std::string ply = test::tmp_path("render_cli.ply"), png = test::tmp_path("render_cli.png");
  write_mesh(ply, sphere, a);
  std::string err;
  REQUIRE(test::run_cli("render " + ply + " --scalar height --size 120x100 --view 0,-1,0.3 --out " + png, nullptr,
                        &err) == 0);
  const Image image = read_png(png);
  CHECK(image.width == 120);
  CHECK(image.height == 100);
  CHECK(err.find("coloured by 'height'") != std::string::npos);
  // The extension in any case, as read_mesh takes it: the scalars are still read.
  const std::string upper = test::tmp_path("render_cli_upper.PLY");
  write_mesh(upper, sphere, a);
  REQUIRE(test::run_cli("render " + upper + " --scalar height --size 64 --out " + png, nullptr, &err) == 0);
  CHECK(err.find("coloured by 'height'") != std::string::npos);
  CHECK(test::run_cli("render " + ply + " --scalar curvature --out " + png, nullptr, &err) == 1);
  CHECK(err.find("no scalar 'curvature'; it has: H height") != std::string::npos);
  CHECK(test::run_cli("render " + ply + " --view 1,2 --out " + png, nullptr, &err) == 1);
  CHECK(err.find("expected 3 comma-separated numbers") != std::string::npos);
  CHECK(test::run_cli("render " + ply + " --size 10 --out " + png, nullptr, &err) == 1);
  CHECK(err.find("width 10 is outside") != std::string::npos);
}
#endif

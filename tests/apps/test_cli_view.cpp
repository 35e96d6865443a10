// corrlap view, and the pages the other commands write beside their pictures: regularize's and
// reconstruct's view.html (--no-view skips it), a study's index.html. What the page does in a
// browser: tests/viewer/browser_test.mjs.
#include <doctest/doctest.h>

#include <corrlap/io/mesh_io.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <corrlap/render/view_page.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

using namespace corrlap;
using namespace corrlap::test;
namespace fs = std::filesystem;

namespace {

std::string fresh(const std::string& name) {
  const std::string dir = tmp_path(name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

nlohmann::json scene_of(const std::string& page_file) {
  const std::string html = read_text(page_file);
  const std::string open = "<script type=\"application/json\" id=\"corrlap-scene\">";
  const std::size_t a = html.find(open);
  REQUIRE(a != std::string::npos);
  const std::size_t b = html.find("</script>", a);
  return nlohmann::json::parse(html.substr(a + open.size(), b - a - open.size()));
}

std::vector<std::string> mesh_names(const nlohmann::json& scene) {
  std::vector<std::string> names;
  for (const auto& m : scene["meshes"]) names.push_back(m["name"]);
  return names;
}

}  // namespace

TEST_CASE("corrlap view: the meshes named by their files, their PLY scalars as fields, errors named") {
  const std::string dir = fresh("cli_view");
  if (!has_viewer()) {
    std::string err;
    REQUIRE(run_cli("digitize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --out " + dir + "/a.obj") == 0);
    CHECK(run_cli("view " + dir + "/a.obj --out " + dir + "/v.html", nullptr, &err) == 1);
    CHECK(err.find("no viewer") != std::string::npos);
    MESSAGE("skipped: this build has no viewer");
    return;
  }
  REQUIRE(run_cli("regularize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --normals true --no-render --no-view --out " +
                  dir + "/r") == 0);
  CHECK(!fs::exists(dir + "/r/view.html"));
  std::string err;
  REQUIRE(run_cli("view " + dir + "/r/input.ply " + dir + "/r/regularized.obj --scalar H --layout overlay --out " +
                      dir + "/v.html",
                  nullptr, &err) == 0);
  CHECK(err.find("wrote " + dir + "/v.html") != std::string::npos);
  const nlohmann::json scene = scene_of(dir + "/v.html");
  CHECK(mesh_names(scene) == std::vector<std::string>{"input", "regularized"});
  CHECK(scene["initial_field"] == "H");
  CHECK(scene["layout"] == "overlay");
  CHECK(scene["meshes"][0]["vertex_fields"].contains("H"));
  CHECK(scene["meshes"][1]["vertex_fields"].empty());  // OBJ carries no scalars
  MeshAttributes attributes;
  const PolygonMesh input = read_mesh(dir + "/r/input.ply", &attributes);
  CHECK(scene["meshes"][0]["vertices"] == input.positions.rows());
  CHECK(scene["meshes"][0]["faces"] == input.faces.size());
  // Two files of one name: the paths as given.
  REQUIRE(run_cli("view " + dir + "/r/regularized.ply " + dir + "/r/regularized.obj --out " + dir + "/w.html") == 0);
  CHECK(mesh_names(scene_of(dir + "/w.html")) ==
        std::vector<std::string>{dir + "/r/regularized.ply", dir + "/r/regularized.obj"});

  // corrlap curvature writes H at the vertices and at the faces: both shown, the face one told apart.
  REQUIRE(run_cli("curvature --shape sphere1 --h 0.5 --bbox -1.5 1.5 --normals true --out " + dir + "/c") == 0);
  REQUIRE(run_cli("view " + dir + "/c/curvature.ply --out " + dir + "/c.html") == 0);
  const nlohmann::json c = scene_of(dir + "/c.html");
  CHECK(c["meshes"][0]["vertex_fields"].contains("H"));
  CHECK(c["meshes"][0]["face_fields"].contains("H (faces)"));

  // The first view, as render's --view and --up (normalized in the scene).
  REQUIRE(run_cli("view " + dir + "/r/regularized.obj --view 0,0,2 --up 0,1,0 --out " + dir + "/top.html") == 0);
  const nlohmann::json top = scene_of(dir + "/top.html");
  CHECK(top["view"]["direction"] == nlohmann::json::array({0.0, 0.0, 1.0}));
  CHECK(top["view"]["up"] == nlohmann::json::array({0.0, 1.0, 0.0}));
  CHECK(run_cli("view " + dir + "/r/regularized.obj --view 0,x,1 --out " + dir + "/x.html", nullptr, &err) == 1);
  CHECK(err.find("--view '0,x,1': 'x' is not a number") != std::string::npos);
  CHECK(run_cli("view " + dir + "/r/regularized.obj --up 0,0,0 --out " + dir + "/x.html", nullptr, &err) == 1);
  CHECK(err.find("view and up directions") != std::string::npos);

  CHECK(run_cli("view " + dir + "/r/regularized.obj --scalar K --out " + dir + "/x.html", nullptr, &err) == 1);
  CHECK(err.find("no surface has a field 'K' (they have none)") != std::string::npos);
  CHECK(run_cli("view " + dir + "/r/input.ply --scalar K --out " + dir + "/x.html", nullptr, &err) == 1);
  CHECK(err.find("the fields are: H") != std::string::npos);
  write_text(dir + "/bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n");
  CHECK(run_cli("view " + dir + "/bad.ply --out " + dir + "/x.html", nullptr, &err) == 1);
  CHECK(err.find("bad.ply") != std::string::npos);
  CHECK(run_cli("view " + dir + "/missing.ply --out " + dir + "/x.html", nullptr, &err) != 0);
  CHECK(err.find("missing.ply") != std::string::npos);
  CHECK(!fs::exists(dir + "/x.html"));
}

TEST_CASE("regularize and reconstruct write view.html, a study folder gets index.html") {
  if (!has_viewer()) return;
  const std::string dir = fresh("cli_view_outputs");
  REQUIRE(run_cli("regularize --shape goursat --h 0.5 --out " + dir + "/g") == 0);
  const nlohmann::json g = scene_of(dir + "/g/view.html");
  CHECK(mesh_names(g) == std::vector<std::string>{"staircase", "regularized"});
  CHECK(g["layout"] == "side");
  CHECK(g["title"] == "regularize: goursat, h=0.5");
  // H in the range of the pictures: the automatic range of H after.
  MeshAttributes after;
  (void)read_mesh(dir + "/g/regularized.ply", &after);
  const ColourScale scale = colour_scale(ScalarField{"H", after.vertex_scalars.at("H"), false}, RenderOptions{});
  REQUIRE(g["fields"][0]["name"] == "H");
  CHECK(g["fields"][0]["min"].get<double>() == scale.min);
  CHECK(g["fields"][0]["max"].get<double>() == scale.max);
  CHECK(g["meshes"][1]["vertex_fields"].contains("displacement"));
  const nlohmann::json metrics = nlohmann::json::parse(read_text(dir + "/g/metrics.json"));
  CHECK(metrics["time_s"].contains("view_s"));

  corrlap::write_obj(dir + "/ico.obj", icosphere(2));
  REQUIRE(run_cli("reconstruct --mesh-file " + dir + "/ico.obj --resolution 8 --subdivide 0 --no-render --out " + dir +
                  "/rec") == 0);
  const nlohmann::json rec = scene_of(dir + "/rec/view.html");
  CHECK(mesh_names(rec) == std::vector<std::string>{"fem", "polydec", "staircase", "fine mesh"});
  std::vector<bool> visible;
  for (const auto& m : rec["meshes"]) visible.push_back(m["visible"]);
  CHECK(visible == std::vector<bool>{true, false, false, false});
  REQUIRE(run_cli("reconstruct --mesh-file " + dir + "/ico.obj --resolution 8 --subdivide 0 --no-view --out " + dir +
                  "/rec2") == 0);
  CHECK(!fs::exists(dir + "/rec2/view.html"));
  CHECK(fs::exists(dir + "/rec2/before.png"));

  std::string out;
  REQUIRE(run_cli("study backward --h 0.5 --methods polydec --functions x2 --no-plots --out " + dir + "/st", &out) ==
          0);
  CHECK(out.find(dir + "/st/index.html") != std::string::npos);
  const std::string index = read_text(dir + "/st/index.html");
  CHECK(index.find("<h2>results.csv</h2>") != std::string::npos);
  CHECK(index.find("<h2>summary.csv</h2>") != std::string::npos);
  CHECK(index.find("<th>method</th>") != std::string::npos);
  CHECK(index.find("<td>polydec</td>") != std::string::npos);
}

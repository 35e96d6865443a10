// The CLI's outputs (docs/cli.md, Outputs): every --out is checked before any computation and
// refused with a named error (exit 1) when it cannot be written; a failing command leaves no new
// file; special files (/dev/null) are written in place as single files and refused as folders.
#include <doctest/doctest.h>

#include <corrlap/io/mesh_io.hpp>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

#ifdef CORRLAP_CLI

namespace {

namespace fs = std::filesystem;
using corrlap::test::run_cli;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

std::string expand(std::string s, const std::string& dir) {
  for (std::size_t p; (p = s.find("{D}")) != std::string::npos;) s.replace(p, 3, dir);
  return s;
}

// A fresh scratch folder (one per test case: ctest runs them as concurrent processes) with a small
// surfel mesh s.obj, a triangle mesh ico.obj and a regular file.
std::string make_inputs(const std::string& name) {
  const std::string dir = tmp_path(name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  REQUIRE(run_cli("digitize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --out " + dir + "/s.obj") == 0);
  corrlap::write_obj(dir + "/ico.obj", corrlap::test::icosphere(2));
  write_text(dir + "/file.txt", "a regular file\n");
  return dir;
}

// Every file and folder under `dir`, relative.
std::set<std::string> snapshot(const std::string& dir) {
  std::set<std::string> s;
  for (const auto& e : fs::recursive_directory_iterator(dir)) s.insert(fs::relative(e.path(), dir).string());
  return s;
}

struct OutputCommand {
  std::string args;  // everything but the output, which follows "--out "
  bool folder;       // --out names a folder (else a file, whose extension follows)
  std::string extension;
};

// Every command with an --out, in a call that would succeed with a good one.
const std::map<std::string, OutputCommand>& output_commands() {
  static const std::map<std::string, OutputCommand> commands = {
      {"digitize", {"digitize --shape sphere1 --h 0.5 --bbox -1.5 1.5", false, ".obj"}},
      {"normals", {"normals --shape sphere1 --h 0.5 --bbox -1.5 1.5", false, ".txt"}},
      {"curvature", {"curvature --shape sphere1 --h 0.5 --bbox -1.5 1.5 --normals true", true, ""}},
      {"operators", {"operators --method polydec --mesh {D}/s.obj", true, ""}},
      {"solve", {"solve --method polydec --shape sphere1 --h 0.5 --bbox -1.5 1.5 --rhs x2", false, ".txt"}},
      {"eigs", {"eigs --method polydec --shape sphere1 --h 0.5 --bbox -1.5 1.5 -k 3", false, ".txt"}},
      {"render", {"render {D}/s.obj --size 64", false, ".png"}},
      {"view", {"view {D}/s.obj", false, ".html"}},
      {"regularize", {"regularize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --no-render", true, ""}},
      {"reconstruct", {"reconstruct --mesh-file {D}/ico.obj --resolution 8 --subdivide 0 --no-render", true, ""}},
      {"study", {"study backward --h 0.5 --methods polydec --functions x2 --no-plots", true, ""}},
  };
  return commands;
}

// The subcommands `corrlap --help` lists whose own --help offers --out.
std::set<std::string> commands_with_out() {
  std::string help;
  REQUIRE(run_cli("--help", &help) == 0);
  std::set<std::string> found;
  const std::size_t start = help.find("Subcommands:");
  REQUIRE(start != std::string::npos);
  std::istringstream lines(help.substr(start));
  std::getline(lines, help);  // the heading
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string name;
    if (!(words >> name)) continue;
    std::string sub;
    if (run_cli(name + " --help", &sub) != 0) continue;
    if (sub.find("--out ") != std::string::npos) found.insert(name);
  }
  return found;
}

}  // namespace

TEST_CASE("every command with --out refuses an unusable output before computing: exit 1, the path named") {
  const std::string dir = make_inputs("cli_outputs_walk");
  std::set<std::string> listed;
  for (const auto& [name, c] : output_commands()) listed.insert(name);
  CHECK(commands_with_out() == listed);  // a new command with --out joins the table above

  for (const auto& [name, c] : output_commands()) {
    // A folder output cannot be a file; a file output cannot be a folder (an existing file is
    // replaced, as a re-run does).
    const std::vector<std::string> bad = {c.folder ? dir + "/file.txt" : dir, dir + "/file.txt/sub" + c.extension,
                                          "/proc/corrlap_x" + c.extension};
    for (const std::string& out : bad) {
      const std::string args = expand(c.args, dir) + " --out " + out;
      CAPTURE(args);
      const std::set<std::string> before = snapshot(dir);
      std::string err;
      CHECK(run_cli(args, nullptr, &err) == 1);
      CAPTURE(err);
      CHECK(err.find("internal error") == std::string::npos);
      CHECK(err.find(out) != std::string::npos);
      CHECK(err.find("(--out)") != std::string::npos);
      CHECK(snapshot(dir) == before);
    }
    if (c.folder) {
      std::string err;
      CHECK(run_cli(expand(c.args, dir) + " --out /dev/null", nullptr, &err) == 1);
      CHECK(err.find("'/dev/null' is a special file") != std::string::npos);
    }
  }
}

TEST_CASE("a failing command leaves no new file") {
  const std::string dir = make_inputs("cli_outputs_failing");
  write_text(dir + "/one_normal.txt", "0 0 1\n");
  REQUIRE(run_cli("digitize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --volume-out " + dir + "/in.vol") == 0);
  const std::vector<std::string> failing = {
      // Fails after loading, before writing.
      "regularize --mesh {D}/s.obj --vertex-normals {D}/one_normal.txt --out {D}/reg",
      "regularize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --alpha0 1e300 --out {D}/reg",
      // Fails after input.ply is written: the heat kernel has no vertex regularization.
      "reconstruct --mesh-file {D}/ico.obj --resolution 8 --subdivide 0 --methods heat-kernel --out {D}/rec",
      "reconstruct --mesh-file {D}/ico.obj --resolution 8 --subdivide 0 --methods polydec,heat-kernel --out "
      "{D}/p/q/rec",
      // The second output is refused: the first is not written either.
      "digitize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --volume-out {D}/x.vol --out /dev/null",
      "digitize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --volume-out {D}/x.vol --out {D}/file.txt/x.obj",
      // Fails after the volume is written: a volume has no true normals.
      "digitize --volume {D}/in.vol --threshold 0 --volume-out {D}/x.vol --out {D}/x.ply --normals true",
      // Fails in the study, after study.json is written: inward normals.
      "study backward --h 0.5 --methods fem --normals ii --no-plots --out {D}/st",
  };
  for (const std::string& call : failing) {
    const std::string args = expand(call, dir);
    CAPTURE(args);
    const std::set<std::string> before = snapshot(dir);
    std::string err;
    const int rc = run_cli(args, nullptr, &err);
    CAPTURE(err);
    CHECK(rc == 1);
    CHECK(err.find("internal error") == std::string::npos);
    CHECK(snapshot(dir) == before);
  }
}

TEST_CASE("a re-run into an existing folder replaces its files and keeps the user's") {
  const std::string dir = make_inputs("cli_outputs_rerun");
  const std::string out = dir + "/ops";
  REQUIRE(run_cli("operators --method polydec --mesh " + dir + "/s.obj --out " + out) == 0);
  write_text(out + "/notes.txt", "mine\n");
  write_text(out + "/L.mtx", "stale\n");
  REQUIRE(run_cli("operators --method polydec --mesh " + dir + "/s.obj --out " + out + "/") == 0);
  CHECK(corrlap::test::read_text(out + "/notes.txt") == "mine\n");
  CHECK(corrlap::test::read_text(out + "/L.mtx").rfind("%%MatrixMarket", 0) == 0);
  CHECK(snapshot(dir).count("ops/M.mtx") == 1);
  // Nothing else beside it: the temporary folder is gone.
  std::set<std::string> top;
  for (const auto& e : fs::directory_iterator(dir)) top.insert(e.path().filename().string());
  CHECK(top == std::set<std::string>{"file.txt", "ico.obj", "ops", "s.obj"});
}

TEST_CASE("a single-file output may be /dev/null, which stays a device") {
  const std::string dir = make_inputs("cli_outputs_dev_null");
  std::string err;
  CHECK(run_cli("eigs --method polydec --shape sphere1 --h 0.5 --bbox -1.5 1.5 -k 3 --out /dev/null", nullptr, &err) ==
        0);
  CHECK(fs::is_character_file("/dev/null"));
  CHECK(run_cli("normals --mesh " + dir + "/s.obj --normals trivial --out /dev/null", nullptr, &err) == 0);
  CHECK(fs::is_character_file("/dev/null"));
}

TEST_CASE("info reports triangle meshes: counts, boundary and manifold facts") {
  const std::string dir = make_inputs("cli_outputs_info");
  std::string out, err;
  REQUIRE(run_cli("info --json " + dir + "/ico.obj", &out, &err) == 0);
  auto j = nlohmann::json::parse(out);
  CHECK(j["vertices"] == 162);
  CHECK(j["faces"] == 320);
  CHECK(j["edges"] == 480);
  CHECK(j["euler"] == 2);
  CHECK(j["genus"] == 0);
  CHECK(j["closed"] == true);
  CHECK(j["manifold"] == true);
  CHECK(j["faces_kind"] == "triangles");
  // The icosphere's area is below the sphere's 4 pi and close to it.
  CHECK(j["area"].get<double>() < 4 * M_PI);
  CHECK(j["area"].get<double>() > 0.97 * 4 * M_PI);
  // Open (one face removed) and non-manifold (two tetrahedra sharing a vertex).
  corrlap::PolygonMesh open = corrlap::test::icosphere(1);
  open.faces.pop_back();
  corrlap::write_obj(dir + "/open.obj", open);
  REQUIRE(run_cli("info --json " + dir + "/open.obj", &out, &err) == 0);
  j = nlohmann::json::parse(out);
  CHECK(j["boundary_edges"] == 3);
  CHECK(j["closed"] == false);
  CHECK(j["genus"] == -1);
  write_text(dir + "/bowtie.obj",
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv -1 0 0\nv 0 -1 0\nv 0 0 -1\n"
             "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 1 5 6\nf 1 7 5\nf 1 6 7\nf 5 7 6\n");
  REQUIRE(run_cli("info --json " + dir + "/bowtie.obj", &out, &err) == 0);
  j = nlohmann::json::parse(out);
  CHECK(j["nonmanifold_vertices"] == 1);
  CHECK(j["nonmanifold_edges"] == 0);
  CHECK(j["components"] == 1);
  CHECK(j["manifold"] == false);
  REQUIRE(run_cli("info " + dir + "/ico.obj", &out, &err) == 0);
  CHECK(out.find("genus                 0") != std::string::npos);
}

TEST_CASE("render --scalar none draws a file whose only NaN is in a scalar it does not use") {
  const std::string dir = make_inputs("cli_outputs_render_nan");
  write_text(dir + "/nan.ply",
             "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
             "property float q\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0 1\n1 0 0 nan\n0 1 0 2\n0 0 1 3\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  std::string err;
  CHECK(run_cli("render " + dir + "/nan.ply --scalar none --size 64 --out " + dir + "/nan.png", nullptr, &err) == 0);
  CHECK(fs::exists(dir + "/nan.png"));
  // The scalar itself, used, is refused by name.
  CHECK(run_cli("render " + dir + "/nan.ply --scalar q --size 64 --out " + dir + "/q.png", nullptr, &err) == 1);
  CHECK(err.find("'q' is not finite") != std::string::npos);
  CHECK_FALSE(fs::exists(dir + "/q.png"));
}

#endif

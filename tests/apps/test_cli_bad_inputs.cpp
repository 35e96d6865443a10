// The CLI's bad-input catalogue: every subcommand, wrong options, missing and corrupt files, bad
// normals, bad configs. Each case must fail with a named error (exit 1 for corrlap's errors, CLI11's
// parse codes for malformed options), never crash, never print "internal error", and the message
// must contain the expected fragment. Add a case whenever a new way to fail is found.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "test_support.hpp"

#ifdef CORRLAP_CLI

namespace {

using corrlap::test::run_cli;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

struct BadCall {
  std::string args;      // after "corrlap"; {D} is replaced by the scratch folder
  std::string expected;  // fragment of the message on stderr
};

std::string expand(std::string s, const std::string& dir) {
  for (std::size_t p; (p = s.find("{D}")) != std::string::npos;) s.replace(p, 3, dir);
  return s;
}

// Scratch folder with the files the cases read: a valid small surfel mesh and its face normals,
// and a set of broken files. One folder per test case: ctest runs the cases as concurrent
// processes, and one rewriting the files while another reads them failed now and then.
std::string make_inputs(const std::string& folder) {
  const std::string dir = tmp_path(folder);
  std::filesystem::create_directories(dir);
  REQUIRE(run_cli("digitize --shape sphere1 --h 0.5 --bbox -1.5 1.5 --out " + dir + "/s.obj --face-normals " + dir +
                  "/fn.txt") == 0);
  write_text(dir + "/garbage.obj", "garbage\n");
  write_text(dir + "/empty.obj", "");
  write_text(dir + "/oob.obj", "v 0 0 0\nf 1 2 3\n");
  write_text(dir + "/one_normal.txt", "0 0 1\n");
  write_text(dir + "/nan_normal.txt", "nan 0 1\n");
  write_text(dir + "/typo.json", R"({"solver": "cholmod", "tolerence": 1})");
  write_text(dir + "/broken.json", "{bad json");
  write_text(dir + "/trunc.vol", "X: 2\n");
  write_text(dir + "/trunc.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n0\n");
  write_text(dir + "/trunc.off", "OFF\n3 1 0\n0 0 0\n");
  write_text(dir + "/float.nrrd", "NRRD0004\ntype: block\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n");
  write_text(dir + "/short.raw", std::string(7, '\0'));
  write_text(dir + "/model.stl", "solid x\n");
  write_text(dir + "/three_values.txt", "1\n2\n3\n");
  write_text(dir + "/huge_count.ply",
             "ply\nformat binary_little_endian 1.0\nelement vertex 4294967296\nproperty float x\nend_header\n");
  write_text(dir + "/huge_count.off", "OFF\n100000000 100000000 0\n0 0 0\n");
  write_text(dir + "/no_end.vol", "X: 2\nY: 2\nZ: 2\nVoxel-Size: 1\n");
  write_text(dir + "/big.vol", "X: 1024\nY: 1024\nZ: 1024\nVoxel-Size: 1\nAlpha-Color: 0\nVersion: 2\n.\n");
  write_text(dir + "/bad_sizes.nrrd", "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 -2 2\nencoding: raw\n\n");
  write_text(dir + "/no_faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  return dir;
}

const std::vector<BadCall>& catalogue() {
  static const std::vector<BadCall> calls = {
      // No or unknown command.
      {"", "subcommand is required"},
      {"nosuchcommand", "nosuchcommand"},
      {"--threads -3 info {D}/s.obj", "--threads: must be a number >= 0 (got -3)"},
      {"--threads abc info {D}/s.obj", "'abc' is not a number"},
      // The memory budget (--max-memory): malformed, and requests beyond it refused before allocating.
      {"--max-memory abc info {D}/s.obj", "memory size 'abc': expected a positive size"},
      {"--max-memory 0 info {D}/s.obj", "memory size '0'"},
      {"--max-memory 1M digitize --shape sphere1 --h 0.01 --out {D}/x.obj",
       "more than the memory budget of 1.0 MiB (max_memory); use a larger grid step or a smaller box"},
      {"--max-memory 64M digitize --shape sphere1 --h 0.004 --bbox -1.2 1.2 --offset 1 --out {D}/x.obj",
       "surface extraction of"},
      {"--max-memory 64M digitize --volume {D}/big.vol --threshold 0 --out {D}/x.obj",
       "voxels as a bit grid needs 136.5 MiB, more than the memory budget of 64.0 MiB"},
      // digitize: sources and parameters.
      {"digitize --out {D}/x.obj", "Exactly 1 option from [--shape,--polynomial,--volume,--mesh-file] is required"},
      {"digitize --shape sphere1 --volume {D}/trunc.vol --out {D}/x.obj", "2 were given"},
      {"digitize --shape nosuch --h 0.1 --out {D}/x.obj", "unknown shape 'nosuch'"},
      {"digitize --polynomial \"x^2+\" --h 0.1 --out {D}/x.obj", "unexpected end of expression"},
      {"digitize --polynomial \"x^^2\" --h 0.1 --out {D}/x.obj", "polynomial \"x^^2\""},
      {"digitize --shape sphere1 --h -1 --out {D}/x.obj", "--h: must be a positive number (got -1)"},
      {"digitize --shape sphere1 --h 0 --out {D}/x.obj", "--h: must be a positive number (got 0)"},
      {"digitize --shape sphere1 --h inf --out {D}/x.obj", "--h: must be a positive number (got inf)"},
      {"digitize --shape sphere1 --h abc --out {D}/x.obj", "--h: 'abc' is not a number"},
      {"digitize --shape sphere1 --h 1e-6 --bbox -1.5 1.5 --out {D}/x.obj", "too large for h = 1e-06"},
      {"digitize --shape sphere1 --h 0.1 --bbox 1 -1 --out {D}/x.obj", "bounding box needs finite MIN < MAX"},
      {"digitize --shape sphere1 --h 0.1 --offset -2 --out {D}/x.obj", "--offset: must be a number >= 0"},
      {"digitize --shape sphere1 --h 0.1 --center 0 0 --out {D}/x.obj", "--center"},
      {"digitize --shape sphere1 --h 0.1 --out {D}/x.xyz", "unsupported extension 'xyz' for writing"},
      // digitize: volumes.
      {"digitize --volume {D}/missing.vol --threshold 0 --out {D}/x.obj", "missing.vol': cannot open"},
      {"digitize --volume {D}/trunc.vol --threshold 0 --out {D}/x.obj", "trunc.vol'"},
      {"digitize --volume {D}/short.raw --threshold 0 --out {D}/x.obj", "need their dimensions (raw_dimensions"},
      {"digitize --volume {D}/short.raw --raw-dimensions 2 2 2 --threshold 0 --out {D}/x.obj", "short.raw'"},
      {"digitize --volume {D}/float.nrrd --threshold 0 --out {D}/x.obj", "unsupported type 'block'"},
      {"digitize --volume {D}/model.stl --threshold 0 --out {D}/x.obj", "unsupported extension 'stl'"},
      {"digitize --volume {D}/no_end.vol --threshold 0 --out {D}/x.obj", "no_end.vol'"},
      {"digitize --volume {D}/big.vol --threshold 0 --out {D}/x.obj", "the file holds"},
      {"digitize --volume {D}/bad_sizes.nrrd --threshold 0 --out {D}/x.obj", "bad_sizes.nrrd'"},
      {"digitize --volume " + corrlap::test::reference_dir() +
           "/bad_inputs/nrrd_sizes_wrap_ascii.nrrd --threshold 0 "
           "--out {D}/x.obj",
       "4 295 032 832 voxels"},
      {"digitize --volume " + corrlap::test::reference_dir() +
           "/bad_inputs/nrrd_gzip_1gib.nrrd --threshold 0 "
           "--out {D}/x.obj",
       "of gzip data can hold"},
      // digitize: mesh files.
      {"digitize --mesh-file {D}/s.obj --out {D}/x.obj", "--mesh-file needs --resolution N"},
      {"digitize --mesh-file {D}/s.obj --resolution 0 --out {D}/x.obj", "--resolution: must be a positive number"},
      {"digitize --mesh-file {D}/trunc.ply --resolution 16 --out {D}/x.obj", "trunc.ply'"},
      {"digitize --mesh-file {D}/trunc.off --resolution 16 --out {D}/x.obj", "trunc.off'"},
      {"digitize --mesh-file {D}/missing.obj --resolution 16 --out {D}/x.obj", "missing.obj': cannot open"},
      {"digitize --mesh-file {D}/huge_count.ply --resolution 16 --out {D}/x.obj", "absurd element count 4294967296"},
      {"digitize --mesh-file {D}/huge_count.off --resolution 16 --out {D}/x.obj", "the file holds"},
      {"digitize --mesh-file {D}/no_faces.obj --resolution 16 --out {D}/x.obj", "no_faces.obj'"},
      // info.
      {"info", "file is required"},
      {"info {D}/missing.obj", "missing.obj': cannot open"},
      {"info {D}/garbage.obj", "garbage.obj': no vertex"},
      {"info {D}/empty.obj", "empty.obj': no vertex"},
      {"info {D}/oob.obj", "face index 2 out of range"},
      {"info {D}/model.stl", "unsupported extension 'stl'"},
      // normals.
      // The old spelling (a hidden alias) is checked by the library, whose message names the new flag.
      {"normals --shape sphere1 --h 0.2 --estimator nosuch --out {D}/n.txt", "unknown normal source 'nosuch'"},
      {"normals --shape sphere1 --h 0.2 --estimator ii --at nowhere --out {D}/n.txt", "--at: nowhere not in"},
      {"normals --mesh {D}/s.obj --estimator true --out {D}/n.txt", "true normals need an implicit shape"},
      {"normals --shape sphere1 --h 0.2 --normals nosuch --out {D}/n.txt", "--normals: nosuch not in"},
      {"normals --shape sphere1 --h 0.2 --ii-radius -1 --out {D}/n.txt", "--ii-radius: must be a positive number"},
      {"normals --mesh {D}/s.obj --normals true --out {D}/n.txt", "true normals need an implicit shape (--normals)"},
      // curvature.
      {"curvature --shape sphere1 --h 0.2 --normals true --radius -1 --out {D}/c", "--radius: must be a number >= 0"},
      {"curvature --mesh {D}/s.obj --normals true --out {D}/c", "--mesh needs exactly one of --face-normals"},
      // operators: methods, normals, parameters, configs.
      {"operators --method nosuch --mesh {D}/s.obj --out {D}/o", "unknown discretization 'nosuch'"},
      {"operators --method fem --mesh {D}/s.obj --out {D}/o", "fem needs face normals"},
      {"operators --method fem --mesh {D}/s.obj --face-normals {D}/one_normal.txt --out {D}/o", "1 rows, expected"},
      {"operators --method fem --mesh {D}/s.obj --face-normals {D}/nan_normal.txt --out {D}/o", "non-finite"},
      {"operators --method fem --mesh {D}/s.obj --face-normals {D}/missing.txt --out {D}/o",
       "missing.txt': cannot open"},
      {"operators --method fem --shape sphere1 --h 0.2 --normals bogus --out {D}/o", "--normals: bogus not in"},
      {"operators --method fem --shape sphere1 --h 0.2 --normals true --param nosuch=1 --out {D}/o",
       "unknown config key 'nosuch'"},
      {"operators --method fem --shape sphere1 --h 0.2 --normals true --config {D}/broken.json --out {D}/o",
       "broken.json': invalid JSON"},
      {"operators --method fem --shape sphere1 --h 0.2 --normals true --config {D}/missing.json --out {D}/o",
       "missing.json': cannot open"},
      {"operators --method fem --shape sphere1 --h 0.2 --normals true --mass nosuch --out {D}/o",
       "fem: mass = 'nosuch': expected one of full | lumped (--mass)"},
      {"operators --method fem --shape sphere1 --h 0.2 --normals true --param orientation=sideways --out {D}/o",
       "fem: orientation = 'sideways': expected one of clamp | warn | error (--orientation)"},
      {"operators --method interpolated --shape sphere1 --h 0.2 --normals true --lambda -1 --out {D}/o",
       "interpolated: lambda = -1: expected >= 0 (--lambda)"},
      {"operators --method interpolated --shape sphere1 --h 0.2 --normals true --kappa nan --out {D}/o",
       "interpolated: kappa = 'nan': expected a number (--kappa)"},
      {"operators --method heat-kernel --shape sphere1 --h 0.2 --normals true --t -1 --out {D}/o",
       "heat-kernel: t = -1: expected > 0 (--t)"},
      // solve.
      {"solve --method fem --shape sphere1 --h 0.2 --normals true --rhs nosuch",
       "--rhs 'nosuch': neither a test function"},
      {"solve --method fem --shape sphere1 --h 0.2 --normals true --rhs {D}/three_values.txt", "3 values"},
      {"solve --method fem --shape sphere1 --h 0.2 --normals true --rhs x2 --solver nosuch",
       "unknown linear solver 'nosuch'"},
      {"solve --method fem --shape sphere1 --h 0.2 --normals true --rhs x2 --config {D}/typo.json",
       "unknown config key 'tolerence'"},
      {"solve --method fem --shape sphere1 --h 0.2 --normals true --rhs x2 --param tolerance=1",
       "unknown config key 'tolerance'"},
      {"solve --method polydec --shape sphere1 --h 0.2 --rhs x2 --config {D}/broken.json", "invalid JSON"},
      {"solve --method fem --shape sphere1 --h 0.2 --normals true --rhs x2 --orientation sideways",
       "fem: orientation = 'sideways': expected one of clamp | warn | error (--orientation)"},
      // A solver failing on operators assembled from inconsistent normals used as given names the
      // cause and the remedy (torus, h = 0.25, true normals: 16 corners with u.n <= 0).
      {"solve --method interpolated --shape torus --h 0.25 --normals true --orientation warn --rhs x2",
       "remedy: --orientation clamp (the default)"},
      // eigs.
      {"eigs --method fem --shape sphere1 --h 0.2 --normals true -k 0", "-k must be positive"},
      {"eigs --method fem --shape sphere1 --h 0.2 --normals true -k 100000", "k = 100000 must be in"},
      {"eigs --method fem --shape sphere1 --h 0.2 --normals true -k 5 --solver nosuch",
       "unknown linear solver 'nosuch'"},
      {"eigs --method fem --mesh {D}/s.obj --face-normals {D}/fn.txt -k 3 --shift 5", "--shift"},
      // backends.
      {"backends --nosuch", "--nosuch"},
      // Outputs (docs/cli.md, Outputs): refused before any computation, the path and the flag named.
      {"regularize --shape sphere1 --h 0.5 --out {D}/s.obj", "output folder '{D}/s.obj' is an existing file"},
      {"regularize --shape sphere1 --h 0.5 --out {D}/s.obj/sub", "lies under '{D}/s.obj', which is a file"},
      {"regularize --shape sphere1 --h 0.5 --out /proc/corrlap_x", "output folder '/proc/corrlap_x': cannot create"},
      {"regularize --shape sphere1 --h 0.5 --out /dev/null", "'/dev/null' is a special file"},
      {"reconstruct --mesh-file {D}/s.obj --out {D}/s.obj", "is an existing file; the output is a folder"},
      {"study backward --h 0.5 --out {D}/s.obj", "output folder '{D}/s.obj' is an existing file"},
      {"operators --method polydec --mesh {D}/s.obj --out {D}/s.obj/o",
       "which is a file, not a folder; choose a path in a folder (--out)"},
      {"curvature --shape sphere1 --h 0.5 --normals true --out /proc/corrlap_x", "/proc/corrlap_x"},
      {"normals --shape sphere1 --h 0.5 --out {D}", "output file '{D}' is an existing folder; name a file (--out)"},
      {"normals --shape sphere1 --h 0.5 --out {D}/missing/n.txt", "the folder '{D}/missing' does not exist"},
      {"digitize --shape sphere1 --h 0.5 --volume-out {D}/x.vol --out /dev/null",
       "mesh file '/dev/null': unsupported extension '' for writing"},
      {"digitize --shape sphere1 --h 0.5 --volume-out {D}/s.obj/x.vol --out {D}/x.obj", "(--volume-out)"},
      {"digitize --shape sphere1 --h 0.5 --face-normals {D} --out {D}/x.obj", "is an existing folder"},
      // render: the size quoted as given.
      {"render {D}/s.obj --size 10x --out {D}/x.png", "--size '10x': expected WIDTHxHEIGHT or WIDTH in whole pixels"},
      {"render {D}/s.obj --size x10 --out {D}/x.png", "--size 'x10'"},
      {"render {D}/s.obj --size 10.5 --out {D}/x.png", "--size '10.5'"},
  };
  return calls;
}

}  // namespace

TEST_CASE("CLI bad-input catalogue: every case fails with a named error, never a crash or an internal error") {
  const std::string dir = make_inputs("bad_inputs_cli");
  CHECK(catalogue().size() >= 50);
  for (const BadCall& call : catalogue()) {
    const std::string args = expand(call.args, dir);
    CAPTURE(args);
    std::string err;
    const int rc = run_cli(args, nullptr, &err);
    CAPTURE(err);
    CHECK(rc != 0);
    CHECK(rc != 2);   // "internal error"
    CHECK(rc < 128);  // no signal
    CHECK(err.find("internal error") == std::string::npos);
    CHECK(err.find(expand(call.expected, dir)) != std::string::npos);
  }
}

TEST_CASE("JSON reports survive file names that are not UTF-8") {
  const std::string dir = make_inputs("bad_inputs_cli_utf8");
  const std::string name = dir + "/latin1_\xe9t\xe9.obj";  // "été" in Latin-1: invalid UTF-8
  std::filesystem::copy_file(dir + "/s.obj", name, std::filesystem::copy_options::overwrite_existing);
  std::string out, err;
  REQUIRE(run_cli("info --json '" + name + "'", &out, &err) == 0);
  CHECK(err.find("internal error") == std::string::npos);
  CHECK(out.find("\"faces\"") != std::string::npos);
  CHECK(out.find("latin1_") != std::string::npos);  // the name, its invalid bytes replaced
}

#endif

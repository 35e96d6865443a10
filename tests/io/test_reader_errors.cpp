// Fuzz-style tests: every reader rejects malformed, truncated, empty and absurdly sized input with
// an InputError (IoError) whose message names the file and the problem; random truncations and
// byte flips of valid files never crash nor throw anything but InputError.
#include <doctest/doctest.h>

#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <functional>
#include <random>

#include "test_support.hpp"

using namespace corrlap;
using corrlap::test::read_text;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {

using Reader = std::function<void(const std::string&)>;

struct BadCase {
  std::string content;
  std::string expected;  // fragment of the message naming the problem
};

// Every case must throw InputError with the file name and the expected fragment in the message.
void check_bad(const char* format, const std::string& ext, const Reader& read, const std::vector<BadCase>& cases) {
  int i = 0;
  for (const BadCase& c : cases) {
    const std::string path = tmp_path(std::string("bad_") + format + "_" + std::to_string(i++) + "." + ext);
    write_text(path, c.content);
    CAPTURE(path);
    CAPTURE(c.expected);
    bool threw = false;
    try {
      read(path);
    } catch (const InputError& e) {
      threw = true;
      const std::string m = e.what();
      CAPTURE(m);
      CHECK(m.find(path) != std::string::npos);
      CHECK(m.find(c.expected) != std::string::npos);
    }
    CHECK(threw);
  }
}

// Truncations at many lengths and random byte changes of a valid file: the reader either returns
// or throws InputError (never a crash, std::bad_alloc or another exception type).
void fuzz(const char* format, const std::string& ext, const Reader& read, const std::string& valid, unsigned seed) {
  std::mt19937 rng(seed);
  const std::string path = tmp_path(std::string("fuzz_") + format + "." + ext);
  int errors = 0, cases = 0;
  auto attempt = [&](const std::string& content) {
    write_text(path, content);
    ++cases;
    try {
      read(path);
    } catch (const InputError& e) {
      ++errors;
      CHECK(std::string(e.what()).find(path) != std::string::npos);
    }
  };
  for (std::size_t n = 0; n < valid.size(); n += std::max<std::size_t>(1, valid.size() / 60))
    attempt(valid.substr(0, n));
  const char* junk = "\0\n -9e9x.#/\xff";
  for (int k = 0; k < 150; ++k) {
    std::string s = valid;
    const int flips = 1 + int(rng() % 3);
    for (int f = 0; f < flips; ++f) s[rng() % s.size()] = junk[rng() % 12];
    attempt(s);
  }
  CHECK(errors > 0);  // the empty file at least
  MESSAGE(std::string(format) << ": " << cases << " mutated files, " << errors << " rejected");
}

std::string binary_ply_header(int nv, int nf) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(nv) +
         "\nproperty double x\nproperty double y\nproperty double z\nelement face " + std::to_string(nf) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

const char* kTet = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

}  // namespace

TEST_CASE("OBJ reader rejects bad files, naming file and problem") {
  check_bad("obj", "obj", [](const std::string& p) { read_mesh(p); },
            {{"", "no vertex"},
             {"# only a comment\n", "no vertex"},
             {"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no face"},
             {"v 0 0\nf 1 2 3\n", "line 1: vertex with fewer than 3 coordinates"},
             {"v 0 0 x\n", "malformed or non-finite coordinate 'x'"},
             {"v 0 0 nan\n", "non-finite"},
             {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "line 4: face with fewer than 3 corners"},
             {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: face index 4 out of range (3 vertices)"},
             {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "face index -4 out of range"},
             {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n", "malformed face index 'a'"},
             {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", "malformed face index"}});
  CHECK_THROWS_WITH_AS(read_mesh(tmp_path("does_not_exist.obj")), doctest::Contains("cannot open"), IoError);
  CHECK_THROWS_WITH_AS(read_mesh(tmp_path("mesh.stl")), doctest::Contains("unsupported extension 'stl'"), IoError);
  fuzz(
      "obj", "obj", [](const std::string& p) { read_mesh(p); }, kTet, 1);
}

TEST_CASE("PLY reader rejects bad files, naming file and problem") {
  const std::string ascii_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::string bin = binary_ply_header(3, 1);
  for (double d : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0}) bin.append(reinterpret_cast<const char*>(&d), 8);
  const std::string bin_faceless = bin;
  bin.push_back(char(3));
  for (int id : {0, 1, 2}) bin.append(reinterpret_cast<const char*>(&id), 4);
  std::string bad_id = bin;
  bad_id[bad_id.size() - 4] = char(7);  // last index 7 (3 vertices)
  std::string huge_count = bin;
  huge_count[bin_faceless.size()] = char(250);  // 250 corners announced, 3 present
  check_bad(
      "ply", "ply", [](const std::string& p) { read_ply(p); },
      {{"", "empty file"},
       {"plx\n", "not a PLY file"},
       {"ply\nformat ascii 1.0\nelement vertex 3\n", "not terminated by end_header"},
       {"ply\nelement vertex 1\nend_header\n", "no format line"},
       {"ply\nformat binary_big_endian 1.0\nend_header\n", "unsupported format binary_big_endian"},
       {"ply\nformat ascii 2.0\nend_header\n", "unsupported PLY version"},
       {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element"},
       {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "unknown property type 'quad'"},
       {"ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n", "absurd element count 99999999999"},
       {"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "malformed element count '-1'"},
       {"ply\nformat ascii 1.0\nwhatever\nend_header\n", "unknown header keyword 'whatever'"},
       {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 "
        "0 0\n",
        "no 'face' element"},
       {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0\n3 0 0 0\n",
        "no scalar property 'z'"},
       {ascii_head + "0 0 0\n1 0 0\n0 1 0\n", "truncated data"},
       {ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "truncated data"},
       {ascii_head + "0 0 0\n1 0 zz\n0 1 0\n3 0 1 2\n", "malformed number 'zz'"},
       {ascii_head + "0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n", "vertex 1: non-finite value of 'z'"},
       {ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
        "face 0, property 'vertex_indices': vertex index 3 out of range (3 vertices)"},
       {ascii_head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "face 0 has 2 corners"},
       {ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n", "non-integer value '2.5'"},
       {ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n4 4 4\n", "trailing data"},
       {binary_ply_header(100000000, 200000000) + "abc", "element 'vertex' announces 100 000 000 entries"},
       {bin_faceless, "truncated"},
       {bin.substr(0, bin.size() - 2), "truncated data: list length 3, the rest of the file holds at most 2 values"},
       {bad_id, "vertex index 7 out of range"},
       {huge_count, "truncated data: list length 250"},
       {bin + "xx", "trailing data"}});
  // the fuzz base is a valid file
  const std::string valid = tmp_path("valid_bin.ply");
  write_text(valid, bin);
  CHECK(read_ply(valid).faces.size() == 1);
  fuzz(
      "ply-binary", "ply", [](const std::string& p) { read_ply(p); }, bin, 2);
  fuzz(
      "ply-ascii", "ply", [](const std::string& p) { read_ply(p); }, ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 3);
}

TEST_CASE("OFF reader rejects bad files, naming file and problem") {
  check_bad("off", "off", [](const std::string& p) { read_off(p); },
            {{"", "empty file"},
             {"# nothing\n\n", "empty file"},
             {"PLY\n", "not an OFF file"},
             {"4OFF\n1 1 0\n", "unsupported OFF variant"},
             {"OFF\n", "missing the counts line"},
             {"OFF\n3\n", "malformed counts line"},
             {"OFF\n3 x 0\n", "malformed counts line"},
             {"OFF\n99999999999 1 0\n", "absurd counts"},
             {"OFF\n0 1 0\n", "no vertex"},
             {"OFF\n3 0 0\n0 0 0\n", "no face"},
             {"OFF\n3 1 0\n0 0 0\n1 0 0\n", "need at least 26 B, more than the 22 B the file holds"},
             {"OFF\n3 1 0\n0 0 0\n1 0 0\n\n\n\n\n\n", "truncated: expected 3 vertices, got 2"},
             {"OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", "vertex 1 has fewer than 3 coordinates"},
             {"OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n", "vertex 1: malformed or non-finite coordinate 'inf'"},
             {"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "truncated: expected 2 faces, got 1"},
             {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "face 0: malformed corner count '2'"},
             {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "face 0: announces 4 corners, line has 3"},
             {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "face 0: vertex index 3 out of range (3 vertices)"},
             {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", "vertex index -1 out of range"},
             {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 b\n", "malformed index 'b'"}});
  fuzz(
      "off", "off", [](const std::string& p) { read_off(p); },
      "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n", 4);
}

TEST_CASE("volume readers reject bad files, naming file and problem") {
  VolumeReadOptions raw_opts;
  raw_opts.raw_dimensions = Eigen::Vector3i(2, 2, 2);
  const std::string vol_head = "X: 2\nY: 2\nZ: 2\n.\n";
  check_bad("vol", "vol", [](const std::string& p) { read_volume(p); },
            {{"", "header not terminated"},
             {"X: 2\nY: 2\nZ: 2\n", "header not terminated by a '.' line"},
             {"X 2\n.\n", "malformed header line 'X 2'"},
             {"X: 2\nY: 2\n.\n", "header has no 'Z' field"},
             {"X: 2\nY: -2\nZ: 2\n.\n", "invalid dimension Y: '-2'"},
             {"X: 2\nY: two\nZ: 2\n.\n", "invalid dimension Y: 'two'"},
             {"X: 1000000\nY: 1000000\nZ: 1000000\n.\n", "absurdly large"},
             {"X: 2000\nY: 2000\nZ: 2000\n.\n",
              "truncated data: sizes 2000 x 2000 x 2000 = 8 000 000 000 voxels need 7.5 GiB, more than the 0 B the "
              "file holds"},
             {vol_head + "1234567", "truncated data"}});
  check_bad("raw", "raw", [&](const std::string& p) { read_volume(p, raw_opts); },
            {{"", "truncated data"},
             {"1234567", "sizes 2 x 2 x 2 = 8 voxels need 8 B, more than the 7 B the file holds"},
             {"123456789", "larger than the given dimensions"}});
  check_bad("raw-nodims", "raw", [](const std::string& p) { read_volume(p); }, {{"12345678", "need their dimensions"}});
  VolumeReadOptions absurd;
  absurd.raw_dimensions = Eigen::Vector3i(1 << 20, 1 << 20, 1 << 20);
  check_bad("raw-absurd", "raw", [&](const std::string& p) { read_volume(p, absurd); },
            {{"12345678", "absurdly large"}});
  const std::string nh = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\n";
  check_bad(
      "nrrd", "nrrd", [](const std::string& p) { read_volume(p); },
      {{"", "empty file"},
       {"P5\n2 2\n", "not a NRRD file"},
       {nh + "encoding: raw\n", "header not terminated by a blank line"},
       {"NRRD0004\ntype: uint8\nsizes: 2 2 2\nencoding: raw\n\n12345678", "no 'dimension' field"},
       {"NRRD0004\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n12345678", "no 'type' field"},
       {nh + "\n12345678", "no 'encoding' field"},
       {"NRRD0004\ntype: block\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n12345678", "unsupported type 'block'"},
       {"NRRD0004\ntype: uint8\ndimension: 2\nsizes: 2 2\nencoding: raw\n\n1234", "dimension must be 3, got '2'"},
       {"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2\nencoding: raw\n\n1234", "malformed 'sizes' field"},
       {"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 0 2\nencoding: raw\n\n", "invalid size 0 on axis 1"},
       {"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 100000 100000 100000\nencoding: raw\n\n", "absurdly large"},
       {nh + "encoding: bzip2\n\n12345678", "unsupported encoding 'bzip2'"},
       {nh + "encoding: raw\nendian: middle\n\n12345678", "invalid endian 'middle'"},
       {nh + "encoding: raw\n\n1234567", "truncated data"},
       {nh + "encoding: raw\n\n123456789", "larger than the announced sizes"},
       {nh + "data file: x.raw\nencoding: raw\n\n", "cannot open its data file"},
       {nh + "encoding: ascii\n\n1 2 3 4 5 6 7 8 9", "more ascii values"},
       {nh + "encoding: ascii\n\n1 2 3 4 5 6 7 300", "ascii value 300 out of range"},
       {nh + "encoding: ascii\n\n1 2 3 x 5 6 7 8", "malformed ascii data at value 3"},
       {nh + "encoding: ascii\n\n1 2", "need at least 15 B, more than the 3 B the file holds"},
       {nh + "encoding: gzip\n\nnot gzip at all", "gzip"},
       {nh + "type 2\nencoding: raw\n\n12345678", "malformed header line 'type 2'"}});
  fuzz(
      "vol", "vol", [](const std::string& p) { read_volume(p); }, vol_head + "12345678", 5);
  fuzz(
      "nrrd", "nrrd", [](const std::string& p) { read_volume(p); }, nh + "encoding: raw\n\n12345678", 6);
}

TEST_CASE("text readers (normals, scalars, Matrix Market, config) reject bad files") {
  check_bad("normals", "txt", [](const std::string& p) { read_normals(p); },
            {{"", "no data (empty file)"},
             {"# only comments\n\n", "no data"},
             {"1 0 0\n0 1\n", "line 2: expected 3 numbers, got 2"},
             {"1 0 0\n0 1 0 0\n", "line 2: expected 3 numbers, got 4"},
             {"1 0 x\n", "line 1: malformed or non-finite number 'x'"},
             {"1 0 inf\n", "non-finite number 'inf'"}});
  check_bad(
      "scalars", "txt", [](const std::string& p) { read_scalars(p); },
      {{"", "no data"}, {"1\n2 3\n", "line 2: expected 1 numbers, got 2"}, {"1e999\n", "malformed or non-finite"}});
  check_bad("mm", "mtx", [](const std::string& p) { read_matrix_market(p); },
            {{"", "missing %%MatrixMarket header"},
             {"hello\n", "missing %%MatrixMarket header"},
             {"%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n", "only real coordinate"},
             {"%%MatrixMarket matrix coordinate complex general\n", "only real coordinate"},
             {"%%MatrixMarket matrix coordinate real general\n", "malformed size line"},
             {"%%MatrixMarket matrix coordinate real general\n2 2\n", "malformed size line"},
             {"%%MatrixMarket matrix coordinate real general\n2 2 1 junk\n1 1 1\n", "malformed size line"},
             {"%%MatrixMarket matrix coordinate real general\n-2 2 1\n", "malformed size line"},
             {"%%MatrixMarket matrix coordinate real general\n3000000000 3000000000 1\n1 1 1\n", "absurd size line"},
             {"%%MatrixMarket matrix coordinate real general\n2 2 5\n1 1 1\n", "absurd size line"},
             {"%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n",
              "line 4, entry 2: truncated: end of file after 1 of 2 declared entries"},
             {"%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1.0abc\n",
              "line 3, entry 1: malformed entry '1 1 1.0abc'"},
             {"%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1\n",
              "entry 1: index (3, 1) out of range for a 2 x 2 matrix"},
             {"%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 nan\n", "line 3, entry 1: value not finite"}});
  check_bad("config", "json", [](const std::string& p) { Config::from_json_file(p); },
            {{"", "empty file"},
             {"  \n", "empty file"},
             {"{\"a\": 1", "invalid JSON"},
             {"[1, 2]", "expected a JSON object"},
             {"{\"a\": [1]}", "value of key 'a' must be a string, a number or a boolean"},
             {"{\"a\": {\"b\": 1}}", "value of key 'a'"}});
  std::string mm = "%%MatrixMarket matrix coordinate real general\n3 3 3\n1 1 1.5\n2 3 -2\n3 3 4e-3\n";
  fuzz(
      "matrix-market", "mtx", [](const std::string& p) { read_matrix_market(p); }, mm, 7);
  fuzz(
      "normals", "txt", [](const std::string& p) { read_normals(p); }, "1 0 0\n0 1 0\n0 0.6 0.8\n", 8);
  fuzz(
      "config", "json", [](const std::string& p) { Config::from_json_file(p); },
      "{\"solver\": \"cholmod\", \"t\": 0.5, \"x\": true}", 9);
}

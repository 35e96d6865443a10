// A mesh file written in pieces (io/mesh_parts.hpp) is write_mesh's file byte for byte, whatever
// the pieces; its checks are write_mesh's.
#include <doctest/doctest.h>

#include <array>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/mesh_parts.hpp>
#include <limits>
#include <map>
#include <random>

#include "test_support.hpp"

using namespace corrlap;
using corrlap::test::read_text;
using corrlap::test::tmp_path;

namespace {

// A closed quad mesh (a cube's 6 faces subdivided 3 x 3) with coordinates that need all 17 digits.
SurfelMesh quad_mesh() {
  SurfelMesh m;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<Eigen::RowVector3d> points;
  std::map<std::array<int, 3>, int> index;
  const auto vertex = [&](int x, int y, int z) {
    const auto [it, added] = index.try_emplace({x, y, z}, int(points.size()));
    if (added) points.push_back(Eigen::RowVector3d(x / 3.0 + u(rng), y / 7.0 + u(rng), z * 1e5 + u(rng)));
    return it->second;
  };
  std::vector<std::array<int, 4>> faces;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side <= 3; side += 3)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          std::array<int, 4> f;
          const int corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
          for (int c = 0; c < 4; ++c) {
            int p[3];
            p[axis] = side;
            p[(axis + 1) % 3] = a + corners[c][0];
            p[(axis + 2) % 3] = b + corners[c][1];
            f[std::size_t(c)] = vertex(p[0], p[1], p[2]);
          }
          faces.push_back(f);
        }
  m.positions.resize(Eigen::Index(points.size()), 3);
  for (std::size_t v = 0; v < points.size(); ++v) m.positions.row(Eigen::Index(v)) = points[v];
  m.faces.resize(Eigen::Index(faces.size()), 4);
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int c = 0; c < 4; ++c) m.faces(Eigen::Index(f), c) = faces[f][std::size_t(c)];
  return m;
}

// The file assembled from runs cut at `vertex_cuts` and `face_cuts` (sorted ids).
std::string in_pieces(const std::string& path, const SurfelMesh& m, const MeshAttributes& a,
                      std::vector<Eigen::Index> vertex_cuts, std::vector<Eigen::Index> face_cuts) {
  const MeshFileLayout layout = mesh_file_layout(path, m.num_vertices(), m.num_faces(), a);
  std::string file = mesh_file_header(layout);
  vertex_cuts.push_back(m.num_vertices());
  Eigen::Index begin = 0;
  for (Eigen::Index end : vertex_cuts) {
    MeshAttributes part;
    if (a.vertex_normals.rows()) part.vertex_normals = a.vertex_normals.middleRows(begin, end - begin);
    for (const auto& [name, v] : a.vertex_scalars) part.vertex_scalars[name] = v.segment(begin, end - begin);
    file += mesh_file_vertices(layout, begin, m.positions.middleRows(begin, end - begin), part);
    begin = end;
  }
  face_cuts.push_back(m.num_faces());
  begin = 0;
  for (Eigen::Index end : face_cuts) {
    const QuadFaces faces = m.faces.middleRows(begin, end - begin).cast<std::int64_t>();
    file += mesh_file_faces(layout, faces);
    begin = end;
  }
  return file;
}

}  // namespace

TEST_CASE("a mesh file written in pieces is write_mesh's file, byte for byte") {
  const SurfelMesh m = quad_mesh();
  REQUIRE(m.num_vertices() == 56);
  MeshAttributes a;
  a.vertex_normals = m.positions.rowwise().normalized();
  a.vertex_scalars["H"] = m.positions.col(0);
  a.vertex_scalars["displacement"] = m.positions.col(2).array().abs();
  a.comments = {"SPACE=RAS", "units mm"};
  for (const std::string ext : {"ply", "obj"}) {
    CAPTURE(ext);
    const std::string whole = tmp_path("mesh_parts_whole." + ext);
    write_mesh(whole, m, a);
    const std::string expected = read_text(whole);
    CHECK(in_pieces(whole, m, a, {}, {}) == expected);
    CHECK(in_pieces(whole, m, a, {1, 2, 30, 55}, {17, 18, 40}) == expected);
    MeshAttributes plain;
    write_mesh(whole, m, plain);
    CHECK(in_pieces(whole, m, plain, {10}, {5}) == read_text(whole));
  }
}

TEST_CASE("mesh file pieces refuse what write_mesh refuses") {
  const SurfelMesh m = quad_mesh();
  MeshAttributes a;
  CHECK_THROWS_AS(mesh_file_layout(tmp_path("x.off"), 3, 1, a), IoError);
  a.comments = {"two\nlines"};
  CHECK_THROWS_AS(mesh_file_layout(tmp_path("x.ply"), 3, 1, a), IoError);
  CHECK_THROWS_AS(mesh_file_layout(tmp_path("x.obj"), 3, 1, a), IoError);
  a.comments.clear();
  a.vertex_scalars["nx"] = Eigen::VectorXd::Zero(3);
  CHECK_THROWS_AS(mesh_file_layout(tmp_path("x.ply"), 3, 1, a), IoError);
  a.vertex_scalars.clear();
  a.face_scalars["area"] = Eigen::VectorXd::Zero(1);
  CHECK_THROWS_AS(mesh_file_layout(tmp_path("x.ply"), 3, 1, a), IoError);

  const MeshFileLayout ply = mesh_file_layout(tmp_path("x.ply"), m.num_vertices(), m.num_faces(), MeshAttributes{});
  Eigen::MatrixX3d bad = m.positions.topRows(4);
  bad(2, 1) = std::numeric_limits<double>::quiet_NaN();
  try {
    (void)mesh_file_vertices(ply, 20, bad, MeshAttributes{});
    FAIL("a NaN position was written");
  } catch (const IoError& e) {
    CHECK(std::string(e.what()).find("vertex 22 is not finite") != std::string::npos);
  }
  CHECK_THROWS_AS(mesh_file_vertices(ply, m.num_vertices() - 2, m.positions.topRows(4), MeshAttributes{}), IoError);
  MeshAttributes unexpected;
  unexpected.vertex_scalars["H"] = Eigen::VectorXd::Zero(4);
  CHECK_THROWS_AS(mesh_file_vertices(ply, 0, m.positions.topRows(4), unexpected), IoError);
  QuadFaces faces = m.faces.topRows(2).cast<std::int64_t>();
  faces(1, 3) = m.num_vertices();
  CHECK_THROWS_AS(mesh_file_faces(ply, faces), IoError);
}

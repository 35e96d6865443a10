// Mesh voxelization: exact counts on boxes, agreement with the generalized winding number
// (solid angles) on spheres, robustness to soups, flips, holes and overlaps; the bunny.
#include <doctest/doctest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/mesh_voxelization.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "test_support.hpp"

using namespace corrlap;

namespace {

// Box [lo, hi] as 12 outward-oriented triangles.
PolygonMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  PolygonMesh m;
  m.positions.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    m.positions.row(i) << ((i & 1) ? hi.x() : lo.x()), ((i & 2) ? hi.y() : lo.y()), ((i & 4) ? hi.z() : lo.z());
  // quads counter-clockwise seen from outside, fanned into triangles
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.faces.push_back({q[0], q[1], q[2]});
    m.faces.push_back({q[0], q[2], q[3]});
  }
  return m;
}

// Volume and area of a closed triangle mesh (divergence theorem).
double mesh_volume(const PolygonMesh& m) {
  double vol = 0;
  for (const auto& f : m.faces) {
    const Eigen::Vector3d a = m.positions.row(f[0]), b = m.positions.row(f[1]), c = m.positions.row(f[2]);
    vol += a.dot(b.cross(c)) / 6.0;
  }
  return vol;
}
double mesh_area(const PolygonMesh& m) {
  double area = 0;
  for (const auto& f : m.faces) {
    const Eigen::Vector3d a = m.positions.row(f[0]), b = m.positions.row(f[1]), c = m.positions.row(f[2]);
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

// Generalized winding number by solid angles (Van Oosterom-Strackee): an independent inside test.
double winding_number(const PolygonMesh& m, const Eigen::Vector3d& p) {
  double w = 0;
  for (const auto& f : m.faces) {
    const Eigen::Vector3d a = Eigen::Vector3d(m.positions.row(f[0])) - p,
                          b = Eigen::Vector3d(m.positions.row(f[1])) - p,
                          c = Eigen::Vector3d(m.positions.row(f[2])) - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    w += 2 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return w / (4 * M_PI);
}

PolygonMesh transformed(PolygonMesh m, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  for (Eigen::Index i = 0; i < m.positions.rows(); ++i)
    m.positions.row(i) = (R * m.positions.row(i).transpose() + t).transpose();
  return m;
}

bool same_voxels(const VoxelGrid& a, const VoxelGrid& b) {
  if (a.lower() != b.lower() || a.upper() != b.upper()) return false;
  for (int z = a.lower().z(); z <= a.upper().z(); ++z)
    for (int y = a.lower().y(); y <= a.upper().y(); ++y)
      for (std::size_t w = 0; w < a.words_per_row(); ++w)
        if (a.row(y, z)[w] != b.row(y, z)[w]) return false;
  return true;
}

std::string bunny_path() {
  if (const char* env = std::getenv("CORRLAP_BUNNY")) return env;
  // The build tree records the source directory; data/bunny/ lives there (scripts/fetch_bunny.sh).
  std::ifstream cache(std::string(CORRLAP_TEST_TMP) + "/../../CMakeCache.txt");
  std::string line;
  while (std::getline(cache, line))
    if (line.rfind("corrlap_SOURCE_DIR:STATIC=", 0) == 0) return line.substr(26) + "/data/bunny/bunny.obj";
  return "";
}

}  // namespace

TEST_CASE("voxelized box has exactly the grid centres of the half-open box (edges and vertices hit exactly)") {
  // Cube [-1,1]^3 at h = 1/8: every coordinate is dyadic, rays run exactly along the faces, through
  // the diagonal edges and the vertices. The perturbation rule puts a centre on the low faces
  // inside and on the high faces outside: 16 centres per axis.
  MeshVoxelizationParams p;
  p.h = 0.125;
  MeshVoxelizationReport r;
  const VoxelGrid g = voxelize_mesh(box_mesh({-1, -1, -1}, {1, 1, 1}), p, &r);
  CHECK(g.count() == 16 * 16 * 16);
  CHECK(r.closed());
  CHECK(r.ambiguous_voxels == 0);
  CHECK(r.warnings().empty());
  CHECK(g.get(-8, -8, -8));
  CHECK_FALSE(g.get(8, 0, 0));
  CHECK(g.lower() == Eigen::Vector3i::Constant(-9));
  CHECK(g.upper() == Eigen::Vector3i::Constant(9));
  // resolution: longest side 2 = 16 voxels gives the same h
  MeshVoxelizationParams q;
  q.resolution = 16;
  CHECK(same_voxels(voxelize_mesh(box_mesh({-1, -1, -1}, {1, 1, 1}), q), g));
  // a box off the grid: count = product of the numbers of centres k*h in [lo, hi)
  const Eigen::Vector3d lo(-0.83, 0.217, -2.05), hi(1.37, 0.9, -0.31);
  p.h = 0.1;
  std::int64_t expected = 1;
  for (int c = 0; c < 3; ++c) {
    int n = 0;
    for (int k = -100; k <= 100; ++k) n += (k * p.h >= lo[c] && k * p.h < hi[c]);
    expected *= n;
  }
  CHECK(voxelize_mesh(box_mesh(lo, hi), p).count() == expected);
}

TEST_CASE("inside test equals the generalized winding number (solid angles) on a rotated sphere") {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const PolygonMesh m =
      transformed(test::icosphere(3, 1.0, Eigen::Vector3d::Zero()), R, Eigen::Vector3d(0.31, -0.12, 0.05));
  MeshVoxelizationParams p;
  p.resolution = 14;
  MeshVoxelizationReport r;
  const VoxelGrid g = voxelize_mesh(m, p, &r);
  CHECK(r.closed());
  CHECK(r.inconsistent_edges == 0);
  CHECK(r.self_intersections == 0);
  int checked = 0, disagree = 0;
  for (int z = g.lower().z(); z <= g.upper().z(); ++z)
    for (int y = g.lower().y(); y <= g.upper().y(); ++y)
      for (int x = g.lower().x(); x <= g.upper().x(); ++x) {
        const double w = winding_number(m, g.h() * Eigen::Vector3d(x, y, z));
        if (std::abs(w - 0.5) < 1e-6) continue;  // on the surface: either answer is right
        ++checked;
        disagree += (w > 0.5) != g.get(x, y, z);
      }
  CHECK(checked > 3000);
  CHECK(disagree == 0);
}

TEST_CASE("voxel volume of a sphere converges to the polyhedron volume") {
  const PolygonMesh m = test::icosphere(4, 1.0, Eigen::Vector3d(0.013, 0.027, -0.041));
  const double V = mesh_volume(m), A = mesh_area(m);
  for (double h : {0.1, 0.05}) {
    CAPTURE(h);
    MeshVoxelizationParams p;
    p.h = h;
    const double vox = double(voxelize_mesh(m, p).count()) * h * h * h;
    // Bound: a tenth of the boundary layer (area * h); an inside test wrong on a whole layer of
    // voxels or a whole row would exceed it.
    CHECK(std::abs(vox - V) < 0.1 * A * h);
    MESSAGE("h = " << h << ": voxel volume " << vox << ", polyhedron " << V << ", rel. error "
                   << std::abs(vox - V) / V);
  }
}

TEST_CASE("triangle soups, flipped orientation and polygon faces give the same voxels") {
  const PolygonMesh m = test::icosphere(2, 1.0, Eigen::Vector3d(0.1, 0.2, 0.3));
  MeshVoxelizationParams p;
  p.resolution = 20;
  const VoxelGrid ref = voxelize_mesh(m, p);
  // soup: every triangle has its own copies of its vertices
  PolygonMesh soup;
  soup.positions.resize(Eigen::Index(3 * m.faces.size()), 3);
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k)
      soup.positions.row(Eigen::Index(3 * f + std::size_t(k))) = m.positions.row(m.faces[f][std::size_t(k)]);
    soup.faces.push_back({int(3 * f), int(3 * f) + 1, int(3 * f) + 2});
  }
  MeshVoxelizationReport rs;
  CHECK(same_voxels(voxelize_mesh(soup, p, &rs), ref));
  CHECK(rs.merged_vertices == int(soup.positions.rows() - m.positions.rows()));
  CHECK(rs.closed());
  // flipped: every face reversed
  PolygonMesh flipped = m;
  for (auto f : flipped.faces) std::reverse(f.begin(), f.end());
  MeshVoxelizationReport rf;
  CHECK(same_voxels(voxelize_mesh(flipped, p, &rf), ref));
  CHECK(rf.inward_oriented);
  CHECK(rf.warnings().size() == 1);
  // box given by quads (fanned internally) equals the triangle version
  PolygonMesh quads = box_mesh({-1, -1, -1}, {1, 1, 1});
  PolygonMesh q2;
  q2.positions = quads.positions;
  for (std::size_t f = 0; f < quads.faces.size(); f += 2)
    q2.faces.push_back({quads.faces[f][0], quads.faces[f][1], quads.faces[f][2], quads.faces[f + 1][2]});
  p.resolution = 10;
  CHECK(same_voxels(voxelize_mesh(q2, p), voxelize_mesh(quads, p)));
}

TEST_CASE("open mesh: warning with counts, inside decided by the 6-ray vote") {
  PolygonMesh m = box_mesh({-1, -1, -1}, {1, 1, 1});
  FaceList open;  // without the top face (triangles 2 and 3, z = 1): 4 boundary edges
  for (std::size_t f = 0; f < m.faces.size(); ++f)
    if (f != 2 && f != 3) open.push_back(m.faces[f]);
  m.faces = open;
  MeshVoxelizationParams p;
  p.h = 0.125;
  MeshVoxelizationReport r;
  const VoxelGrid g = voxelize_mesh(m, p, &r);
  CHECK(r.boundary_edges == 4);
  CHECK(r.nonmanifold_edges == 0);
  CHECK_FALSE(r.closed());
  CHECK(g.count() == 4096);  // interior: 5 of 6 rays inside; above the hole: 1 of 6
  REQUIRE_FALSE(r.warnings().empty());
  CHECK(r.warnings()[0].find("not closed: 4 boundary edges, 0 non-manifold edges") != std::string::npos);
}

TEST_CASE("overlapping parts and non-manifold edges are reported, voxels are the union") {
  PolygonMesh a = box_mesh({-1, -1, -1}, {1, 1, 1}), b = box_mesh({0.01, 0.02, 0.03}, {2, 2, 2});
  PolygonMesh both = a;
  both.positions.conservativeResize(16, 3);
  both.positions.bottomRows(8) = b.positions;
  for (auto f : b.faces) {
    for (int& id : f) id += 8;
    both.faces.push_back(f);
  }
  MeshVoxelizationParams p;
  p.h = 0.125;
  MeshVoxelizationReport r;
  const VoxelGrid g = voxelize_mesh(both, p, &r);
  // union of [-1,1) and [0.01..0.03,2) per axis: centres -8..15 minus those of neither box
  const std::int64_t in_a = 16 * 16 * 16, in_b = 15 * 15 * 15, overlap = 7 * 7 * 7;  // b: k = 1..15, overlap k = 1..7
  CHECK(g.count() == in_a + in_b - overlap);
  CHECK(r.closed());
  CHECK(r.ambiguous_voxels == overlap);
  // the two box surfaces cross along a closed polyline
  CHECK(r.self_intersections > 0);
  REQUIRE(r.warnings().size() == 2);
  CHECK(r.warnings()[0].find("overlapping parts: 343 voxels") != std::string::npos);
  CHECK(r.warnings()[1].find("self-intersecting") != std::string::npos);
  // two cubes sharing one edge (merged vertices): 1 non-manifold edge, still voxelized
  PolygonMesh c = box_mesh({1, 1, -1}, {3, 3, 1});
  PolygonMesh touch = a;
  touch.positions.conservativeResize(16, 3);
  touch.positions.bottomRows(8) = c.positions;
  for (auto f : c.faces) {
    for (int& id : f) id += 8;
    touch.faces.push_back(f);
  }
  MeshVoxelizationReport rt;
  const VoxelGrid gt = voxelize_mesh(touch, p, &rt);
  CHECK(rt.nonmanifold_edges == 1);
  CHECK(rt.self_intersections == 0);  // touching along an edge is not a crossing
  CHECK(gt.count() == 2 * 4096);
}

TEST_CASE("voxelization does not depend on the thread count") {
  const PolygonMesh m = test::icosphere(3, 1.0, Eigen::Vector3d(0.05, 0.0, -0.02));
  MeshVoxelizationParams p;
  p.resolution = 40;
  VoxelGrid one;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = voxelize_mesh(m, p);
  }
  CHECK(same_voxels(one, voxelize_mesh(m, p)));
  // open version (vote path) too
  PolygonMesh open = m;
  open.faces.pop_back();
  VoxelGrid one_open;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one_open = voxelize_mesh(open, p);
  }
  CHECK(same_voxels(one_open, voxelize_mesh(open, p)));
}

TEST_CASE("voxelization input errors are clear") {
  MeshVoxelizationParams p;
  p.resolution = 8;
  CHECK_THROWS_WITH_AS(voxelize_mesh(PolygonMesh{}, p), doctest::Contains("no vertex or no face"), InputError);
  PolygonMesh m = box_mesh({0, 0, 0}, {1, 1, 1});
  m.positions(3, 1) = std::nan("");
  CHECK_THROWS_WITH_AS(voxelize_mesh(m, p), doctest::Contains("vertex 3 has a non-finite position"), InputError);
  m = box_mesh({0, 0, 0}, {1, 1, 1});
  std::ranges::copy(std::initializer_list<int>{0, 1, 9}, m.faces[5].begin());  // face 5 is a triangle
  CHECK_THROWS_WITH_AS(voxelize_mesh(m, p), doctest::Contains("face 5 refers to vertex 9"), InputError);
  m = box_mesh({0, 0, 0}, {1, 1, 1});
  CHECK_THROWS_WITH_AS(voxelize_mesh(m, MeshVoxelizationParams{}),
                       doctest::Contains("give a resolution > 0 or a grid step"), InputError);
  MeshVoxelizationParams tiny;
  tiny.h = 1e-9;
  CHECK_THROWS_AS(voxelize_mesh(m, tiny), InputError);  // absurd grid
  MeshVoxelizationParams coarse;
  coarse.h = 10;
  CHECK_THROWS_WITH_AS(voxelize_mesh(box_mesh({0.1, 0.1, 0.1}, {1, 1, 1}), coarse),
                       doctest::Contains("no voxel centre lies inside"), InputError);
}

TEST_CASE("CLI digitize --mesh-file with --resolution or --h") {
  const std::string obj = corrlap::test::tmp_path("cube_for_cli.obj"),
                    out = corrlap::test::tmp_path("cube_digital.obj");
  write_mesh(obj, box_mesh({-1, -1, -1}, {1, 1, 1}));
  std::string err;
  REQUIRE(corrlap::test::run_cli("digitize --mesh-file " + obj + " --resolution 16 --out " + out, nullptr, &err) == 0);
  CHECK(read_mesh(out).faces.size() == 6 * 16 * 16);
  CHECK(err.find("4096 voxels inside") != std::string::npos);
  REQUIRE(corrlap::test::run_cli("digitize --mesh-file " + obj + " --h 0.25 --out " + out, nullptr, &err) == 0);
  CHECK(read_mesh(out).faces.size() == 6 * 8 * 8);
  CHECK(corrlap::test::run_cli("digitize --mesh-file " + obj + " --out " + out, nullptr, &err) == 1);
  CHECK(err.find("--resolution") != std::string::npos);
  CHECK(corrlap::test::run_cli("digitize --mesh-file " + obj + " --h 0.25 --resolution 4", nullptr, &err) == 1);
  CHECK(err.find("not both") != std::string::npos);
  CHECK(corrlap::test::run_cli("digitize --shape sphere1 --h 0.5 --resolution 4", nullptr, &err) == 1);
  CHECK(err.find("--resolution applies to --mesh-file only") != std::string::npos);
  // open mesh: a warning with counts on stderr, exit 0
  PolygonMesh open = box_mesh({-1, -1, -1}, {1, 1, 1});
  open.faces.pop_back();
  const std::string ply = corrlap::test::tmp_path("open_cube.ply");
  write_mesh(ply, open);
  REQUIRE(corrlap::test::run_cli("digitize --mesh-file " + ply + " --resolution 8 --out " + out, nullptr, &err) == 0);
  CHECK(err.find("warning") != std::string::npos);
  CHECK(err.find("3 boundary edges") != std::string::npos);
}

TEST_CASE("Stanford bunny (npm bunny@1.0.1) voxelizes at resolution 128 [needs scripts/fetch_bunny.sh]") {
  const std::string path = bunny_path();
  if (path.empty() || !std::filesystem::exists(path)) {
    MESSAGE("SKIPPED: bunny model absent (" << path << "); run scripts/fetch_bunny.sh to enable this test");
    return;
  }
  const PolygonMesh m = read_mesh(path);
  MeshVoxelizationParams p;
  p.resolution = 128;
  MeshVoxelizationReport r;
  const VoxelGrid g = voxelize_mesh(m, p, &r);
  CHECK(r.closed());
  CHECK(r.inconsistent_edges == 0);
  CHECK(r.ambiguous_voxels == 0);
  CHECK(r.self_intersections == 0);
  const double V = std::abs(mesh_volume(m)), vox = double(g.count()) * std::pow(g.h(), 3);
  CHECK(std::abs(vox - V) < 0.1 * mesh_area(m) * g.h());
  const SurfelMesh s = extract_surface(g);
  const MeshInfo info = compute_mesh_info(s);
  CHECK(info.boundary_edges == 0);
  MESSAGE("bunny: " << m.faces.size() << " triangles, h = " << g.h() << ", " << g.count() << " voxels, "
                    << s.num_faces() << " surfels, volume " << vox << " vs mesh " << V);
}

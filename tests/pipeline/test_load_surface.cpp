// load_surface: every kind of input gives the surface the older direct calls give, with its voxels,
// shape, grid step, voxel frame and provenance; the surface checks have one policy.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <corrlap/corrlap.hpp>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include "test_support.hpp"

using namespace corrlap;

namespace {

// Two 2^3 blocks that touch along one edge only, in a 6 x 6 x 4 array indexed [x][y][z].
std::vector<double> edge_touching_blocks() {
  std::vector<double> values(6 * 6 * 4, 0.0);
  for (int z = 1; z < 3; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) {
        values[std::size_t((x * 6 + y) * 4 + z)] = 1.0;
        values[std::size_t(((x + 2) * 6 + y + 2) * 4 + z)] = 1.0;
      }
  return values;
}

}  // namespace

TEST_CASE("load_surface of an implicit shape: the digitization's surface, its shape and provenance") {
  ImplicitShapeInput in;
  in.shape = "sphere1";
  in.center = Eigen::Vector3d(0.01, 0.02, -0.03);
  in.digitization = {.h = 0.2, .min_aabb = -1.5, .max_aabb = 1.5};
  const LoadedSurface s = load_surface(in);
  const ImplicitShape shape = make_implicit_shape("sphere1", in.center);
  const VoxelGrid grid = digitize(shape, in.digitization);
  const SurfelMesh mesh = extract_surface(grid);
  CHECK(s.mesh.positions == mesh.positions);
  CHECK(s.mesh.faces == mesh.faces);
  REQUIRE(s.grid);
  CHECK(s.grid->count() == grid.count());
  REQUIRE(s.shape);
  CHECK(s.shape_ptr() == &*s.shape);
  CHECK(s.h == 0.2);
  CHECK(s.frame.h() == 0.2);
  CHECK(s.frame.shift() == Eigen::Vector3d::Zero());
  CHECK(s.description == "sphere1, h=0.2");
  in.shape = "x^2+y^2+z^2-1";
  CHECK(describe(SurfaceInput(in)) == "\"x^2+y^2+z^2-1\", h=0.2");
  in.digitization.h = 0.0;
  CHECK_THROWS_WITH_AS(load_surface(in), doctest::Contains("must be positive"), InputError);
  try {
    (void)load_surface(in);
  } catch (const InputError& e) {
    CHECK(e.parameter() == "h");
  }
  in.digitization.h = 0.2;
  in.center = Eigen::Vector3d(30, 0, 0);  // outside the box
  CHECK_THROWS_WITH_AS(load_surface(in), doctest::Contains("no voxel is inside"), InputError);
}

TEST_CASE("load_surface of a volume array equals the volume file, and its frame maps world to file voxels") {
  const std::vector<double> values = edge_touching_blocks();
  Volume volume;
  volume.size = {6, 6, 4};
  volume.values.assign(values.size(), 0);
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 4; ++z)
        volume.values[std::size_t((z * 6 + y) * 6 + x)] = std::uint8_t(255 * values[std::size_t((x * 6 + y) * 4 + z)]);
  const std::string path = test::tmp_path("pipeline_blocks.vol");
  write_volume(path, volume);
  VolumeFileInput file;
  file.path = path;
  VolumeArrayInput array = VolumeArrayInput::c_order(values, {6, 6, 4});
  array.inside = InsideRule::above(0.5);
  const LoadedSurface a = load_surface(file), b = load_surface(array);
  CHECK(a.mesh.positions == b.mesh.positions);
  CHECK(a.mesh.faces == b.mesh.faces);
  CHECK(a.h == 2.0 / 6.0);  // the longest side spans 2
  CHECK(a.frame.shift() == b.frame.shift());
  CHECK(!a.shape);
  CHECK(a.description == path + ", inside: nonzero");
  // The lowest pointel of the first block, voxel (0, 0, 1) of the file, is at index (-0.5, -0.5, 0.5).
  const Eigen::MatrixX3d index = a.frame.to_index(a.mesh.positions);
  CHECK(index.colwise().minCoeff().isApprox(Eigen::RowVector3d(-0.5, -0.5, 0.5)));
  CHECK(a.frame.to_world(Eigen::Vector3d(-0.5, -0.5, 0.5)).isApprox(a.mesh.positions.colwise().minCoeff().transpose()));
  array.h = 0.1;
  CHECK(load_surface(array).h == 0.1);
  array.inside = InsideRule::above(2.0);
  CHECK_THROWS_WITH_AS(load_surface(array), doctest::Contains("empty volume"), InputError);
  CHECK_THROWS_WITH_AS(VolumeArrayInput::c_order(std::span<const double>(values.data(), 5), {6, 6, 4}),
                       doctest::Contains("5 values for 6x6x4 voxels"), InputError);
}

TEST_CASE("a volume array is read in its own type and strides: any order, broadcasts, 64-bit integers") {
  const std::vector<double> values = edge_touching_blocks();
  const LoadedSurface reference = load_surface(VolumeArrayInput::c_order(values, {6, 6, 4}));
  // The same voxels as uint8 in Fortran order (x fastest), and as big-endian-swapped int32.
  std::vector<std::uint8_t> fortran(values.size());
  std::vector<std::int32_t> swapped(values.size());
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 4; ++z) {
        const double v = values[std::size_t((x * 6 + y) * 4 + z)];
        fortran[std::size_t((z * 6 + y) * 6 + x)] = std::uint8_t(200 * v);
        std::uint32_t bits = std::uint32_t(std::int32_t(7 * v));
        bits = (bits >> 24) | ((bits >> 8) & 0xff00u) | ((bits << 8) & 0xff0000u) | (bits << 24);
        swapped[std::size_t((x * 6 + y) * 4 + z)] = std::int32_t(bits);
      }
  VolumeArrayInput f;
  f.size = {6, 6, 4};
  f.data = fortran.data();
  f.type = VoxelValueType::UInt8;
  f.strides = {1, 6, 36};
  f.inside = InsideRule::above(100.0);
  const LoadedSurface a = load_surface(f);
  CHECK(a.mesh.positions == reference.mesh.positions);
  CHECK(a.mesh.faces == reference.mesh.faces);
  VolumeArrayInput s;
  s.size = {6, 6, 4};
  s.data = swapped.data();
  s.type = VoxelValueType::Int32;
  s.byte_swapped = true;
  s.strides = {4 * 24, 4 * 4, 4};
  s.inside = InsideRule::above(6.5);
  const LoadedSurface b = load_surface(s);
  CHECK(b.mesh.faces == reference.mesh.faces);
  // Integers are compared as integers: 2^62 + 1 > 2^62, though both are 2^62 as doubles.
  const std::int64_t big[2] = {std::int64_t(1) << 62, (std::int64_t(1) << 62) + 1};
  VolumeArrayInput one;
  one.size = {1, 1, 1};
  one.type = VoxelValueType::Int64;
  one.inside = InsideRule::above(std::ldexp(1.0, 62));
  one.data = &big[1];
  CHECK(load_surface(one).grid->count() == 1);
  one.data = &big[0];
  CHECK_THROWS_WITH_AS(load_surface(one), doctest::Contains("empty volume"), InputError);
  // A broadcast volume of 1600^3 voxels (every stride 0, one value) is refused before any allocation.
  const double zero = 0.0, nan = std::nan("");
  VolumeArrayInput broadcast;
  broadcast.size = {1600, 1600, 1600};
  broadcast.data = &zero;
  try {
    (void)load_surface(broadcast);
    FAIL("an empty volume was accepted");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("no voxel nonzero (empty volume)") != std::string::npos);
    CHECK(e.parameter() == "threshold");
  }
  broadcast.data = &nan;
  CHECK_THROWS_WITH_AS(load_surface(broadcast), doctest::Contains("value at [0, 0, 0] is NaN"), InputError);
  broadcast.data = &zero;
  broadcast.inside = InsideRule::above(std::numeric_limits<double>::infinity());
  CHECK_THROWS_WITH_AS(load_surface(broadcast), doctest::Contains("threshold = inf must be a finite number"),
                       InputError);
}

TEST_CASE("load_surface of a mesh to voxelize reports its warnings and note through the callbacks") {
  const std::string path = test::tmp_path("pipeline_icosphere.obj");
  write_mesh(path, test::icosphere(2));
  MeshFileInput in;
  in.path = path;
  std::vector<std::string> warnings, notes;
  LoadMessages messages;
  messages.warning = [&](const std::string& w) { warnings.push_back(w); };
  messages.note = [&](const std::string& n) { notes.push_back(n); };
  CHECK_THROWS_WITH_AS(load_surface(in, messages), doctest::Contains("needs a resolution"), InputError);
  in.resolution = 16;
  const LoadedSurface s = load_surface(in, messages);
  CHECK(warnings.empty());  // a closed, consistently oriented mesh
  REQUIRE(notes.size() == 1);
  CHECK(notes[0].find("voxelized " + path + ": 320 triangles") == 0);
  CHECK(s.mesh.num_faces() > 0);
  CHECK(s.grid);
  CHECK(s.description == path + ", resolution 16");
  // A quad mesh: taken as it is, no voxels, h its mean edge length.
  QuadMeshInput quad;
  quad.mesh = s.mesh;
  quad.mesh.h = 0.0;
  const LoadedSurface q = load_surface(quad);
  CHECK(q.mesh.positions == s.mesh.positions);
  CHECK(!q.grid);
  CHECK(q.h == doctest::Approx(s.mesh.h));
  CHECK_THROWS_AS(load_voxels(quad), InputError);
}

TEST_CASE("surface checks: one policy for open and non-manifold surfaces, the boundary from MeshInfo") {
  // Blocks touching along an edge: the extraction splits the edge into two sheets (docs/math.md §1.4).
  const std::vector<double> values = edge_touching_blocks();
  VolumeArrayInput array = VolumeArrayInput::c_order(values, {6, 6, 4});
  array.inside = InsideRule::above(0.5);
  const LoadedSurface s = load_surface(array);
  CHECK(compute_mesh_info(s.mesh).manifold());
  CHECK(compute_mesh_info(s.mesh).components == 2);
  CHECK_NOTHROW(check_regularizable(s.mesh));
  CHECK(boundary_condition(s.mesh).closed());
  // The same quads with vertices merged by position, as a mesh given as it is: refused, with the counts.
  SurfelMesh pinched = s.mesh;
  pinched.surfels.clear();
  std::map<std::array<double, 3>, int> by_position;
  for (int f = 0; f < pinched.num_faces(); ++f)
    for (int c = 0; c < 4; ++c) {
      const Eigen::RowVector3d x = pinched.positions.row(pinched.faces(f, c));
      pinched.faces(f, c) =
          by_position.emplace(std::array<double, 3>{x[0], x[1], x[2]}, pinched.faces(f, c)).first->second;
    }
  CHECK_THROWS_WITH_AS(check_regularizable(pinched), doctest::Contains("not manifold (2 non-manifold edges"),
                       InputError);
  // Half the faces: open.
  SurfelMesh open = s.mesh;
  open.faces.conservativeResize(open.faces.rows() / 2, 4);
  open.surfels.clear();
  const BoundaryCondition bc = boundary_condition(open);
  CHECK(bc.boundary_edges == compute_mesh_info(open).boundary_edges);
  CHECK(bc.boundary_edges > 0);
  CHECK(bc.note().find("natural (zero Neumann)") != std::string::npos);
  CHECK_THROWS_WITH_AS(check_regularizable(open), doctest::Contains("the surface is open"), InputError);
}

TEST_CASE("resolve_normals takes normals in memory like files, and names the parameter at fault") {
  ImplicitShapeInput in;
  in.shape = "sphere1";
  in.digitization = {.h = 0.2, .min_aabb = -1.5, .max_aabb = 1.5};
  const LoadedSurface s = load_surface(in);
  NormalRequest truth;
  truth.source = NormalSource::True;
  const NormalFields t = resolve_normals(s, NormalKind::Vertex, truth);
  NormalRequest given;
  given.source = NormalSource::Given;
  given.face_normals = t.face;
  const NormalFields g = resolve_normals(s, NormalKind::Vertex, given);
  CHECK(g.face == t.face);
  CHECK(g.vertex == t.vertex);  // the same normalized sum
  // Exact: the true face normals, the exact normal at the vertices.
  NormalRequest exact;
  exact.source = parse_normal_source("exact");
  const NormalFields e = resolve_normals(s, NormalKind::Vertex, exact);
  CHECK(e.face == t.face);
  CHECK(e.vertex == exact_vertex_normals(*s.shape, s.mesh));
  // Given without normals, wrong rows, both a file and a matrix.
  const auto parameter_of = [](const auto& f) {
    try {
      f();
    } catch (const InputError& error) {
      return error.parameter();
    }
    return std::string("no error");
  };
  NormalRequest none;
  none.source = NormalSource::Given;
  CHECK_THROWS_WITH_AS(resolve_normals(s, NormalKind::Face, none, "fem"),
                       doctest::Contains("fem needs face normals: give face_normals or a normals source"), InputError);
  CHECK(parameter_of([&] { (void)resolve_normals(s, NormalKind::Face, none, "fem"); }) == "face_normals");
  CHECK(parameter_of([&] { (void)resolve_normals(s, NormalKind::Vertex, none); }) == "vertex_normals");
  NormalRequest short_rows = given;
  short_rows.face_normals = t.face.topRows(3);
  CHECK_THROWS_WITH_AS(resolve_normals(s, NormalKind::Face, short_rows), doctest::Contains("face_normals: 3 rows"),
                       InputError);
  NormalRequest both = given;
  both.face_normals_file = test::reference_dir() + "/sphere1_h0.2/face_normals_true.txt";
  CHECK(parameter_of([&] { (void)resolve_normals(s, NormalKind::Face, both); }) == "face_normals");
  CHECK(parameter_of([] { (void)parse_normal_source("sideways"); }) == "normals");
  NormalRequest ii;
  ii.source = NormalSource::II;
  ii.ii = IIParams{.k = -1.0, .alpha = 0.33};
  CHECK(parameter_of([&] { (void)resolve_normals(s, NormalKind::Face, ii); }) == "ii_radius");
  ii.ii = IIParams{.k = 3.0, .alpha = std::nan("")};
  CHECK(parameter_of([&] { (void)resolve_normals(s, NormalKind::Face, ii); }) == "ii_alpha");
  ii.ii = IIParams{.k = 3.0, .alpha = 0.33};
  QuadMeshInput quad;
  quad.mesh = s.mesh;
  quad.mesh.surfels.clear();
  CHECK(parameter_of([&] { (void)resolve_normals(load_surface(quad), NormalKind::Face, ii); }) == "normals");
}

// Volumes read per slab, the halo, the distributed II normals and mean curvature (distributed/)
// under mpirun with 1, 2 and 4 ranks: every rank also builds the serial grid, surface and normals
// (test only) and checks its share of the distributed ones against them, bit for bit (H: to
// rounding).
#include <doctest/doctest.h>
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/distributed/distributed_curvature.hpp>
#include <corrlap/distributed/distributed_halo.hpp>
#include <corrlap/distributed/distributed_ii_normals.hpp>
#include <corrlap/distributed/distributed_surface.hpp>
#include <corrlap/distributed/near_slab.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/partial_digitization.hpp>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

using namespace corrlap;

namespace {

std::int64_t sum_over_ranks(std::int64_t x) {
  MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  return x;
}

// MPI is started by the first distributed call; the helpers below may come before it.
int world_rank() {
  ensure_petsc_runtime();
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

// A file name every rank agrees on (rank 0's process id), written by rank 0 only.
std::string shared_path(const std::string& name) {
  ensure_petsc_runtime();
  long pid = long(::getpid());
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  return (std::filesystem::temp_directory_path() / ("corrlap_distributed_normals_" + std::to_string(pid) + "_" + name))
      .string();
}

// The box [-10, 10]^3 of the CLI, as tests/mpi/test_distributed.cpp.
DigitizationParams torus_params(double h) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -10.0;
  p.max_aabb = 10.0;
  return p;
}

// The torus digitized, as a 0/255 volume (its box padded by one empty voxel, as a file would be).
Volume torus_volume(double h) {
  const VoxelGrid grid = digitize(make_implicit_shape("torus"), torus_params(h));
  return voxels_to_volume(grid);
}

// A U: two bars along x, two voxels apart in y, joined only at their far end. A ball of radius 4
// on one bar sees the other, so a slab near the open end holds two pieces of one component.
Volume u_volume() {
  Volume v;
  v.size = Eigen::Vector3i(64, 30, 20);
  v.values.assign(std::size_t(v.size.prod()), 0);
  for (int z = 6; z < 14; ++z)
    for (int y = 5; y < 25; ++y)
      for (int x = 4; x < 58; ++x) {
        const bool bar = (y < 13 || y >= 15) && x < 52;
        const bool joint = x >= 52;
        if (bar || joint) v.values[(std::size_t(z) * 30 + std::size_t(y)) * 64 + std::size_t(x)] = 255;
      }
  return v;
}

// The volume written by rank 0 in the file's format, visible to every rank on return.
std::string written(const Volume& v, const std::string& name) {
  const std::string path = shared_path(name);
  if (world_rank() == 0) {
    if (name.find(".vol") != std::string::npos) {
      write_volume(path, v);
    } else {
      VolumeData d;
      d.size = v.size;
      d.bytes = v.values;
      write_volume_data(path, d);
    }
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return path;
}

void remove_shared(const std::string& path) {
  MPI_Barrier(MPI_COMM_WORLD);
  if (world_rank() == 0) std::remove(path.c_str());
}

// The distributed surface's faces, corner ids and positions are the serial mesh's.
void check_same_surface(const DistributedSurface& d, const SurfelMesh& serial) {
  REQUIRE(d.num_faces == serial.num_faces());
  REQUIRE(d.num_vertices == serial.num_vertices());
  bool same = true;
  for (int f = 0; f < d.mesh.num_faces(); ++f) {
    const std::int64_t id = d.face_ids[std::size_t(f)];
    const Surfel& a = d.mesh.surfels[std::size_t(f)];
    const Surfel& b = serial.surfels[std::size_t(id)];
    same = same && a.lower_voxel == b.lower_voxel && a.axis == b.axis && a.outward == b.outward;
    for (int k = 0; k < 4; ++k) same = same && serial.faces(id, k) == d.vertex_ids[std::size_t(d.mesh.faces(f, k))];
  }
  for (int v = 0; v < d.mesh.num_vertices(); ++v)
    same =
        same && (d.mesh.positions.row(v).array() == serial.positions.row(d.vertex_ids[std::size_t(v)]).array()).all();
  CHECK(same);
  CHECK(sum_over_ranks(d.mesh.num_faces()) == serial.num_faces());
  CHECK(sum_over_ranks(d.num_owned) == serial.num_vertices());
}

// Owned face and vertex normals equal to the serial ones, bit for bit.
void check_same_normals(const DistributedSurface& d, const DistributedNormals& n, const Eigen::MatrixX3d& face,
                        const Eigen::MatrixX3d& vertex) {
  REQUIRE(n.face_normals.rows() == d.mesh.num_faces());
  REQUIRE(n.vertex_normals.rows() == d.num_owned);
  std::int64_t faces_differ = 0, vertices_differ = 0;
  for (int f = 0; f < d.mesh.num_faces(); ++f)
    faces_differ += (n.face_normals.row(f).array() != face.row(d.face_ids[std::size_t(f)]).array()).any() ? 1 : 0;
  for (int v = 0; v < d.num_owned; ++v)
    vertices_differ +=
        (n.vertex_normals.row(v).array() != vertex.row(d.vertex_ids[std::size_t(v)]).array()).any() ? 1 : 0;
  CHECK(sum_over_ranks(faces_differ) == 0);
  CHECK(sum_over_ranks(vertices_differ) == 0);
}

}  // namespace

TEST_CASE("distributed surface of a volume file read per slab: the serial extract_surface of the whole read") {
  const Volume torus = torus_volume(0.35);
  for (const char* name : {"torus.vol", "torus.nii.gz", "torus.npy", "torus.nrrd"}) {
    CAPTURE(name);
    const std::string path = written(torus, name);
    for (const bool centered : {false, true}) {
      VolumeReadOptions options;
      options.centered = centered;
      options.h = centered ? 0.0 : 0.35;
      const SlabSource source = volume_slab_source(path, options);
      const DistributedSurface d = distributed_surface(source);
      const VoxelGrid whole = read_volume_as_voxels(path, options);
      CHECK(source.lower == whole.lower());
      CHECK(source.upper == whole.upper());
      CHECK(d.mesh.h == whole.h());
      check_same_surface(d, extract_surface(whole));
      // Each rank read its slab and one column each side only.
      if (d.ranks > 1) CHECK(d.grid_upper.x() - d.grid_lower.x() + 1 < whole.size().x());
    }
    remove_shared(path);
  }
}

TEST_CASE("distributed halo: the surfels of the widened columns with their serial face and vertex ids") {
  const ImplicitShape shape = make_implicit_shape("torus");
  const SlabSource source = implicit_slab_source(shape, torus_params(0.35));
  const DistributedSurface d = distributed_surface(source);
  const SurfelMesh serial = extract_surface(digitize(shape, torus_params(0.35)));
  for (const int width : {0, 1, 4, 9}) {
    CAPTURE(width);
    const DistributedHalo halo = distributed_halo(source, d, width);
    CHECK(halo.range.first == std::max(source.lower.x(), d.slab.first - width));
    CHECK(halo.range.last == std::min(source.upper.x(), d.slab.last + width));
    CHECK(halo.grid.lower().x() == std::max(source.lower.x(), halo.range.first - 1));
    // Every serial face of the range once, in serial order, with the serial corners at the same pointels.
    std::int64_t in_range = 0;
    for (const Surfel& s : serial.surfels)
      in_range += s.lower_voxel.x() >= halo.range.first && s.lower_voxel.x() <= halo.range.last ? 1 : 0;
    CHECK(halo.mesh.num_faces() == in_range);
    bool same = true, ordered = true, ids = true;
    for (int f = 0; f < halo.mesh.num_faces(); ++f) {
      const std::int64_t id = halo.face_ids[std::size_t(f)];
      const Surfel& a = halo.mesh.surfels[std::size_t(f)];
      const Surfel& b = serial.surfels[std::size_t(id)];
      same = same && a.lower_voxel == b.lower_voxel && a.axis == b.axis && a.outward == b.outward;
      if (f > 0) ordered = ordered && id > halo.face_ids[std::size_t(f - 1)];
      for (int k = 0; k < 4; ++k) {
        const int v = halo.mesh.faces(f, k);
        same = same && (halo.mesh.positions.row(v).array() == serial.positions.row(serial.faces(id, k)).array()).all();
        const std::int64_t vid = halo.vertex_ids[std::size_t(v)];
        ids = ids && (vid < 0 || vid == serial.faces(id, k));
      }
    }
    CHECK(same);
    CHECK(ordered);
    CHECK(ids);
    // The owned faces are found, and their corners all have serial ids.
    REQUIRE(halo.owned_faces.size() == d.face_ids.size());
    bool owned = true;
    for (std::size_t f = 0; f < d.face_ids.size(); ++f) {
      owned = owned && halo.face_ids[std::size_t(halo.owned_faces[f])] == d.face_ids[f];
      for (int k = 0; k < 4; ++k)
        owned = owned && halo.vertex_ids[std::size_t(halo.mesh.faces(halo.owned_faces[f], k))] >= 0;
    }
    CHECK(owned);
    if (d.ranks > 1) CHECK(halo.grid.size().x() < source.upper.x() - source.lower.x() + 1);
  }
  CHECK_THROWS_AS((void)distributed_halo(source, d, -1), InputError);
}

TEST_CASE("distributed II normals of an implicit shape (the paper's parameters) equal the serial ones bit for bit") {
  struct Case {
    const char* name;
    double h;
  };
  // The steps of tests/mpi/test_distributed.cpp, where these surfaces have no pinched pointel.
  for (const Case& c : {Case{"torus", 0.5}, Case{"torus", 0.35}, Case{"goursat", 0.5}, Case{"goursat", 0.3}}) {
    CAPTURE(c.name);
    CAPTURE(c.h);
    const ImplicitShape shape = make_implicit_shape(c.name);
    const SlabSource source = implicit_slab_source(shape, torus_params(c.h));
    const DistributedSurface d = distributed_surface(source);
    const IIParams params = default_ii_params(true);
    const DistributedNormals n = distributed_ii_normals(source, d, params);
    CHECK(n.halo_width == int(std::ceil(ii_digital_radius(c.h, params))) + 2);
    const VoxelGrid grid = digitize(shape, torus_params(c.h));
    const SurfelMesh serial = extract_surface(grid);
    check_same_normals(d, n, ii_face_normals(grid, serial, params), ii_vertex_normals(grid, serial, params));
  }
}

TEST_CASE("distributed II normals of a volume read per slab (default voxel II parameters) equal the serial ones") {
  const std::string path = written(torus_volume(0.35), "torus_ii.nii.gz");
  VolumeReadOptions options;
  options.centered = true;
  options.h = 0.0;
  const SlabSource source = volume_slab_source(path, options);
  const DistributedSurface d = distributed_surface(source);
  const VoxelGrid grid = read_volume_as_voxels(path, options);
  const SurfelMesh serial = extract_surface(grid);
  // The defaults (docs/math.md §7.2's smaller balls on thin parts) and the radius kept everywhere.
  for (const bool shrink : {true, false}) {
    CAPTURE(shrink);
    const IIParams params = default_ii_params(false, {}, {}, shrink);
    const DistributedNormals n = distributed_ii_normals(source, d, params);
    CHECK(n.halo_width == 6);  // r_d = 4 voxels
    check_same_normals(d, n, ii_face_normals(grid, serial, params), ii_vertex_normals(grid, serial, params));
  }
  remove_shared(path);
}

TEST_CASE("distributed II normals on thin parts (docs/math.md §7.2) equal the serial ones bit for bit") {
  // A rod 1.5 voxels in radius, tilted in x and y so that it crosses every slab, beside a thick
  // block: the 4-voxel balls see across the rod, its surfels are estimated again with smaller balls.
  Volume rod;
  rod.size = Eigen::Vector3i(64, 26, 24);
  rod.values.assign(std::size_t(rod.size.prod()), 0);
  const Eigen::Vector3d a(4.0, 7.0, 11.6), b(58.0, 17.0, 12.3);
  for (int z = 0; z < rod.size.z(); ++z)
    for (int y = 0; y < rod.size.y(); ++y)
      for (int x = 0; x < rod.size.x(); ++x) {
        const Eigen::Vector3d p(x, y, z);
        const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
        const bool in_rod = (p - (a + t * (b - a))).norm() <= 1.5;
        const bool in_block = x >= 40 && x < 54 && y >= 2 && y < 9 && z >= 4 && z < 20;
        if (in_rod || in_block) rod.values[(std::size_t(z) * 26 + std::size_t(y)) * 64 + std::size_t(x)] = 255;
      }
  // A speck: an object smaller than the ball, whose balls start below its size.
  Volume speck;
  speck.size = Eigen::Vector3i(12, 8, 8);
  speck.values.assign(std::size_t(speck.size.prod()), 0);
  for (int z = 3; z < 5; ++z)
    for (int y = 3; y < 5; ++y)
      for (int x = 5; x < 7; ++x) speck.values[(std::size_t(z) * 8 + std::size_t(y)) * 12 + std::size_t(x)] = 255;
  for (const auto& [volume, name] : {std::pair{rod, "rod.vol"}, std::pair{speck, "speck.vol"}}) {
    CAPTURE(name);
    const std::string path = written(volume, name);
    VolumeReadOptions options;
    options.h = 0.1;
    const SlabSource source = volume_slab_source(path, options);
    const DistributedSurface d = distributed_surface(source);
    const IIParams params = default_ii_params(false);
    REQUIRE(params.shrink_on_thin_parts);
    const DistributedNormals n = distributed_ii_normals(source, d, params);
    const VoxelGrid grid = read_volume_as_voxels(path, options);
    const SurfelMesh serial = extract_surface(grid);
    const Eigen::MatrixX3d face = ii_face_normals(grid, serial, params);
    check_same_normals(d, n, face, ii_vertex_normals(grid, serial, params));
    // The case runs §7.2: on the rod many faces differ from the kept radius' (on the speck the
    // kept radius is refused: the ball covers it).
    if (std::string(name) == "rod.vol") {
      const Eigen::MatrixX3d kept = ii_face_normals(grid, serial, default_ii_params(false, {}, {}, false));
      int differ = 0;
      for (Eigen::Index f = 0; f < face.rows(); ++f) differ += (face.row(f) - kept.row(f)).norm() > 1e-3 ? 1 : 0;
      MESSAGE("rod: " << differ << " of " << face.rows() << " faces estimated with smaller balls");
      CHECK(differ > face.rows() / 10);
    } else {
      CHECK_THROWS_AS((void)distributed_ii_normals(source, d, default_ii_params(false, {}, {}, false)), InputError);
    }
    remove_shared(path);
  }
}

TEST_CASE("distributed II normals: a component cut by the slabs into pieces joined beyond the halo") {
  const std::string path = written(u_volume(), "u.vol");
  VolumeReadOptions options;
  options.h = 0.05;
  const SlabSource source = volume_slab_source(path, options);
  const DistributedSurface d = distributed_surface(source);
  // The radius kept everywhere, so that the balls see across the gap (docs/math.md §7.2's smaller
  // balls would stay within each bar).
  const IIParams params = default_ii_params(false, {}, {}, /*shrink_on_thin_parts=*/false);
  const DistributedNormals n = distributed_ii_normals(source, d, params);
  const VoxelGrid grid = read_volume_as_voxels(path, options);
  const SurfelMesh serial = extract_surface(grid);
  const Eigen::MatrixX3d face = ii_face_normals(grid, serial, params);
  check_same_normals(d, n, face, ii_vertex_normals(grid, serial, params));
  // With one rank the halo is the whole grid and the U one piece; with more, the slabs near the
  // open end hold both bars unjoined, and the balls between them must add the other bar's moments.
  const std::int64_t joined = sum_over_ranks(n.joined_balls);
  if (d.ranks == 1) CHECK(joined == 0);
  if (d.ranks > 1) CHECK(joined > 0);
  // The bars see each other: restricted to the local piece alone, the normals there would differ
  // (the serial moments without the other bar, computed over a grid holding only one bar's side).
  VoxelGrid cut = grid;
  for (int z = grid.lower().z(); z <= grid.upper().z(); ++z)
    for (int y = grid.lower().y(); y <= grid.upper().y(); ++y)
      for (int x = 52; x <= grid.upper().x(); ++x) cut.set(x, y, z, false);
  const SurfelMesh cut_mesh = extract_surface(cut);
  const Eigen::MatrixX3d cut_face = ii_face_normals(cut, cut_mesh, params);
  std::int64_t differ = 0;
  for (int f = 0; f < cut_mesh.num_faces(); ++f) {
    const Surfel& s = cut_mesh.surfels[std::size_t(f)];
    if (s.lower_voxel.x() > 30 || s.axis != 1) continue;
    // The same surfel in the whole mesh.
    for (int g = 0; g < serial.num_faces(); ++g)
      if (serial.surfels[std::size_t(g)].lower_voxel == s.lower_voxel && serial.surfels[std::size_t(g)].axis == 1) {
        differ += (cut_face.row(f) - face.row(g)).norm() > 1e-3 ? 1 : 0;
        break;
      }
  }
  CHECK(differ > 0);
  remove_shared(path);
}

TEST_CASE("slab sources: a bad file or a slab that fails on one rank fails on every rank, without a hang") {
  CHECK_THROWS_WITH_AS((void)volume_slab_source("/nonexistent/volume.nrrd", {}), doctest::Contains("cannot open"),
                       IoError);
  // The last rank's slab fails (as a memory limit crossed by the widest slab would): it reports its
  // own error, the others name it.
  const ImplicitShape shape = make_implicit_shape("torus");
  SlabSource source = implicit_slab_source(shape, torus_params(0.5));
  int rank = world_rank(), ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const auto digitize_slab = source.voxels;
  source.voxels = [digitize_slab, rank, ranks](int x_first, int x_last) {
    if (rank == ranks - 1) throw IoError("the test's slab failure");
    return digitize_slab(x_first, x_last);
  };
  if (rank == ranks - 1)
    CHECK_THROWS_WITH_AS((void)distributed_surface(source), "the test's slab failure", IoError);
  else
    CHECK_THROWS_WITH_AS((void)distributed_surface(source),
                         doctest::Contains(("rank " + std::to_string(ranks - 1) + " could not read its slab").c_str()),
                         InputError);
}

namespace {

// The near-slab normals and the distributed H against the serial ones: faces bit for bit, vertices
// bit for bit where their fans are whole, H of the owned vertices to rounding.
void check_curvature(const SlabSource& source, const DistributedSurface& d, const VoxelGrid& grid,
                     const SurfelMesh& serial, const IIParams& params, double r, double spacing) {
  CAPTURE(r);
  CAPTURE(spacing);
  const double h = grid.h();
  const int columns = curvature_halo_columns(r, spacing, h);
  const NearSlabNormals near = distributed_ii_normals_near_slab(source, d, params, columns);
  // With the owned faces' normals given, their balls are skipped and nothing changes.
  const Eigen::MatrixX3d owned = distributed_ii_normals(source, d, params).face_normals;
  const NearSlabNormals reused = distributed_ii_normals_near_slab(source, d, params, columns, &owned);
  CHECK((reused.face_normals.array() == near.face_normals.array()).all());
  CHECK((reused.vertex_normals.array() == near.vertex_normals.array()).all());
  const Eigen::MatrixX3d face = ii_face_normals(grid, serial, params);
  const Eigen::MatrixX3d vertex = ii_vertex_normals(grid, serial, params);
  REQUIRE(near.face_ids.size() == std::size_t(near.mesh.num_faces()));
  std::int64_t faces_differ = 0, vertices_differ = 0, vertices_checked = 0;
  for (int f = 0; f < near.mesh.num_faces(); ++f)
    faces_differ += (near.face_normals.row(f).array() != face.row(near.face_ids[std::size_t(f)]).array()).any();
  std::map<std::array<double, 3>, Eigen::Index> serial_vertex;
  for (Eigen::Index v = 0; v < serial.num_vertices(); ++v)
    serial_vertex[{serial.positions(v, 0), serial.positions(v, 1), serial.positions(v, 2)}] = v;
  for (int v = 0; v < near.mesh.num_vertices(); ++v) {
    const int x = near.pointels[std::size_t(v)].x();
    if (x < d.slab.first - columns + 1 || x > d.slab.last + columns) continue;
    const auto it =
        serial_vertex.find({near.mesh.positions(v, 0), near.mesh.positions(v, 1), near.mesh.positions(v, 2)});
    if (it == serial_vertex.end()) {
      ++vertices_differ;  // a vertex the serial surface does not have
      continue;
    }
    ++vertices_checked;
    vertices_differ += (near.vertex_normals.row(v).array() != vertex.row(it->second).array()).any();
  }
  CHECK(sum_over_ranks(faces_differ) == 0);
  CHECK(sum_over_ranks(vertices_differ) == 0);
  CHECK(sum_over_ranks(vertices_checked) >= serial.num_vertices());

  const Eigen::VectorXd H = distributed_mean_curvature(d, near, r, spacing);
  const Eigen::VectorXd expected =
      CorrectedCurvature::interpolated(serial, vertex).mean_curvature_at_sites(r, spacing).H;
  REQUIRE(H.size() == d.num_owned);
  double worst = 0.0;
  for (int v = 0; v < d.num_owned; ++v)
    worst = std::max(worst, std::abs(H[v] - expected[d.vertex_ids[std::size_t(v)]]));
  MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  // The same faces, sites and weights; the walk sums them in another order: 1e-12 of the largest |H|.
  CHECK(worst <= 1e-12 * expected.cwiseAbs().maxCoeff());
  if (columns > 1) {
    const NearSlabNormals narrow = distributed_ii_normals_near_slab(source, d, params, columns - 1);
    CHECK_THROWS_AS((void)distributed_mean_curvature(d, narrow, r, spacing), InputError);
  }
}

}  // namespace

TEST_CASE("distributed mean curvature at sites equals the serial one, from the surface near each slab") {
  // An implicit shape with the paper's II parameters and a volume read per slab with the voxel
  // defaults (smaller balls on thin parts); a radius of a few voxels with every vertex walked, and
  // a larger one whose sites are spaced 4 edges and more apart (cells of docs/math.md §8.4 that
  // cross the slabs' boundaries).
  {
    const ImplicitShape shape = make_implicit_shape("goursat");
    const SlabSource source = implicit_slab_source(shape, torus_params(0.3));
    const DistributedSurface d = distributed_surface(source);
    const VoxelGrid grid = digitize(shape, torus_params(0.3));
    const SurfelMesh serial = extract_surface(grid);
    check_curvature(source, d, grid, serial, default_ii_params(true), 0.9, 0.25 * 0.9);
    check_curvature(source, d, grid, serial, default_ii_params(true), 2.4, 0.5 * 2.4);
  }
  {
    const std::string path = written(torus_volume(0.35), "torus_curvature.nii.gz");
    VolumeReadOptions options;
    options.centered = true;
    options.h = 0.0;
    const SlabSource source = volume_slab_source(path, options);
    const DistributedSurface d = distributed_surface(source);
    const VoxelGrid grid = read_volume_as_voxels(path, options);
    const SurfelMesh serial = extract_surface(grid);
    const double h = grid.h();
    check_curvature(source, d, grid, serial, default_ii_params(false), 12.0 * h, 6.0 * h);
    remove_shared(path);
  }
  {
    // True normals (resolve_normals': the shape's normals at the faces, summed at the vertices), and a spacing of
    // exactly two edges (0.25 r, r = 8 h): the branch between sites and every vertex must not follow the rounding of
    // the mean edge, which differs between the piece and the whole surface.
    const ImplicitShape shape = make_implicit_shape("torus");
    const SlabSource source = implicit_slab_source(shape, torus_params(0.35));
    const DistributedSurface d = distributed_surface(source);
    const SurfelMesh serial = extract_surface(digitize(shape, torus_params(0.35)));
    const double r = 2.8, spacing = 0.25 * r;
    const NearSlabNormals near = true_normals_near_slab(shape, source, d, curvature_halo_columns(r, spacing, 0.35));
    const Eigen::VectorXd H = distributed_mean_curvature(d, near, r, spacing);
    const Eigen::MatrixX3d true_vertex =
        vertex_normals_from_face_normals(true_face_normals(shape, serial), serial.faces, int(serial.num_vertices()));
    const Eigen::VectorXd expected =
        CorrectedCurvature::interpolated(serial, true_vertex).mean_curvature_at_sites(r, spacing).H;
    double worst = 0.0;
    for (int v = 0; v < d.num_owned; ++v)
      worst = std::max(worst, std::abs(H[v] - expected[d.vertex_ids[std::size_t(v)]]));
    MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    CHECK(worst <= 1e-12 * expected.cwiseAbs().maxCoeff());
    CHECK_THROWS_AS((void)true_normals_near_slab(shape, source, d, 0), InputError);
  }
  CHECK_THROWS_AS((void)curvature_halo_columns(0.0, 0.1, 0.1), InputError);
  CHECK_THROWS_AS((void)curvature_halo_columns(1.0, std::nan(""), 0.1), InputError);
}

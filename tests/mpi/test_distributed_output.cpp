// Outputs of the distributed front end without a gather (distributed/distributed_mesh_output.hpp),
// under mpirun with 1, 2 and 4 ranks: rows fetched from and summed at their owners, the result's
// vertex normals, and mesh files written by every rank that equal write_mesh's of the whole
// surface byte for byte.
#include <doctest/doctest.h>
#include <mpi.h>
#include <unistd.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/distributed/distributed_halo.hpp>
#include <corrlap/distributed/distributed_mesh_output.hpp>
#include <corrlap/distributed/distributed_quality.hpp>
#include <corrlap/distributed/distributed_render.hpp>
#include <corrlap/distributed/distributed_surface.hpp>
#include <corrlap/distributed/slab_source.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <corrlap/render/render_mesh.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

using namespace corrlap;

namespace {

DigitizationParams params(double h, double bbox) {
  DigitizationParams p;
  p.h = h;
  p.min_aabb = -bbox;
  p.max_aabb = bbox;
  return p;
}

// A smooth displacement of every vertex by its serial id: positions no rank could guess.
Eigen::RowVector3d moved(const Eigen::RowVector3d& p, std::int64_t id, double h) {
  const double t = double(id);
  return p + 0.3 * h * Eigen::RowVector3d(std::sin(t), std::cos(1.7 * t), std::sin(0.3 * t + 1.0));
}

// A shape's distributed surface, and its serial surface moved by `moved`: the whole, and the rows
// of the rank's owned vertices.
struct MovedSurface {
  ImplicitShape shape;
  DistributedSurface s;
  SurfelMesh staircase, serial;
  Eigen::MatrixX3d owned;  // serial's positions at the owned vertices
};

// The rows of `whole` (one per serial vertex) at the owned vertices.
Eigen::MatrixXd owned_rows(const DistributedSurface& s, const Eigen::MatrixXd& whole) {
  Eigen::MatrixXd out(s.num_owned, whole.cols());
  for (int v = 0; v < s.num_owned; ++v) out.row(v) = whole.row(Eigen::Index(s.vertex_ids[std::size_t(v)]));
  return out;
}

MovedSurface moved_surface(const std::string& name, double h, double bbox) {
  MovedSurface m{make_implicit_shape(name), {}, {}, {}, {}};
  m.s = distributed_surface(m.shape, params(h, bbox));
  m.staircase = extract_surface(digitize(m.shape, params(h, bbox)));
  m.serial = m.staircase;
  for (Eigen::Index v = 0; v < m.serial.positions.rows(); ++v)
    m.serial.positions.row(v) = moved(m.serial.positions.row(v), v, h);
  m.owned = owned_rows(m.s, m.serial.positions);
  return m;
}

std::string shared_name(const std::string& name) {
  long pid = long(::getpid());
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  return (std::filesystem::temp_directory_path() / ("corrlap_mesh_output_" + std::to_string(pid) + "_" + name))
      .string();
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

}  // namespace

TEST_CASE("distributed outputs: rows from their owners, sums at their owners, the result's normals") {
  for (const auto& [shape_name, h, bbox] : {std::tuple{"torus", 0.35, 10.0}, std::tuple{"goursat", 0.3, 10.0}}) {
    CAPTURE(shape_name);
    const MovedSurface m = moved_surface(shape_name, h, bbox);
    const DistributedSurface& s = m.s;
    const SurfelMesh& serial = m.serial;
    const Eigen::MatrixX3d& owned = m.owned;

    // Every local vertex gets its owner's row, bit for bit.
    const Eigen::MatrixXd local = local_rows(s, owned);
    REQUIRE(local.rows() == s.mesh.num_vertices());
    for (Eigen::Index v = 0; v < local.rows(); ++v)
      CHECK((local.row(v).array() == serial.positions.row(Eigen::Index(s.vertex_ids[std::size_t(v)])).array()).all());

    // The owners sum every rank's rows: each vertex's face count is its valence on the whole surface.
    Eigen::MatrixXd faces_here = Eigen::MatrixXd::Zero(s.mesh.num_vertices(), 1);
    for (int f = 0; f < s.mesh.num_faces(); ++f)
      for (int c = 0; c < 4; ++c) faces_here(s.mesh.faces(f, c), 0) += 1.0;
    Eigen::VectorXd valence = Eigen::VectorXd::Zero(serial.num_vertices());
    for (int f = 0; f < serial.num_faces(); ++f)
      for (int c = 0; c < 4; ++c) valence[serial.faces(f, c)] += 1.0;
    const Eigen::MatrixXd summed = sum_at_owners(s, faces_here);
    for (int v = 0; v < s.num_owned; ++v) CHECK(summed(v, 0) == valence[Eigen::Index(s.vertex_ids[std::size_t(v)])]);

    // The serial geometric normals up to the order of the sums (a few roundings of unit vectors).
    const Eigen::MatrixX3d expected = geometric_vertex_normals(serial);
    const Eigen::MatrixX3d normals = distributed_geometric_vertex_normals(s, owned);
    double worst = 0.0;
    for (int v = 0; v < s.num_owned; ++v)
      worst = std::max(worst, (normals.row(v) - expected.row(Eigen::Index(s.vertex_ids[std::size_t(v)]))).norm());
    CHECK(worst <= 1e-14);
  }
}

// goursat, and two balls whose box leaves the first of 4 slabs without surface.
const std::vector<std::tuple<std::string, double, double>> kOutputCases = {
    {"goursat", 0.3, 10.0}, {"(x^2+y^2+z^2-4)*((x-5)^2+y^2+z^2-4)", 0.25, 8.0}};

TEST_CASE("distributed outputs: a mesh file written by every rank is write_mesh's of the whole surface") {
  for (const auto& [shape_name, h, bbox] : kOutputCases) {
    CAPTURE(shape_name);
    const MovedSurface m = moved_surface(shape_name, h, bbox);
    const DistributedSurface& s = m.s;
    const SurfelMesh& serial = m.serial;
    MeshAttributes whole;
    whole.vertex_normals = serial.positions.rowwise().normalized();
    whole.vertex_scalars["H"] = serial.positions.col(0).array().sin();
    whole.vertex_scalars["displacement"] = serial.positions.col(2);
    whole.comments = {"SPACE=LPS"};
    const Eigen::MatrixX3d& owned = m.owned;
    MeshAttributes mine;
    mine.comments = whole.comments;
    for (const auto& [name, v] : whole.vertex_scalars) mine.vertex_scalars[name] = owned_rows(s, v);
    mine.vertex_normals = owned_rows(s, whole.vertex_normals);
    for (const auto& [ext, reversed] : {std::pair{"ply", false}, std::pair{"obj", false}, std::pair{"ply", true}}) {
      CAPTURE(ext);
      CAPTURE(reversed);
      const std::string parts = shared_name(std::string("parts.") + ext),
                        reference = shared_name(std::string("whole.") + ext);
      write_distributed_mesh(parts, s, owned, mine, reversed);
      if (world_rank() == 0) {
        SurfelMesh written = serial;
        if (reversed) written.faces = serial.faces.rowwise().reverse().eval();
        write_mesh(reference, written, whole);
        const std::string expected = bytes_of(reference);
        CHECK(expected.size() > 1000);
        CHECK(bytes_of(parts) == expected);
        CHECK(!std::filesystem::exists(parts + ".partial"));
      }
      MPI_Barrier(MPI_COMM_WORLD);
      if (world_rank() == 0) {
        std::filesystem::remove(parts);
        std::filesystem::remove(reference);
      }
    }

    // A value per vertex: write_scalars' file.
    const std::string scalars = shared_name("values.txt"), scalars_reference = shared_name("values_whole.txt");
    write_distributed_scalars(scalars, s, mine.vertex_scalars.at("H"), {"H: test values"});
    if (world_rank() == 0) {
      write_scalars(scalars_reference, whole.vertex_scalars.at("H"), {"H: test values"});
      CHECK(bytes_of(scalars) == bytes_of(scalars_reference));
      std::filesystem::remove(scalars);
      std::filesystem::remove(scalars_reference);
    }

    // A NaN on the last rank only: the same IoError on every rank, and no file.
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    if (world_rank() == ranks - 1 && s.num_owned > 0)
      mine.vertex_scalars["H"][s.num_owned - 1] = std::numeric_limits<double>::quiet_NaN();
    const std::string failed = shared_name("failed.ply");
    bool thrown = false;
    try {
      write_distributed_mesh(failed, s, owned, mine);
    } catch (const IoError& e) {
      thrown = std::string(e.what()).find("not finite") != std::string::npos;
    }
    CHECK(thrown);
    MPI_Barrier(MPI_COMM_WORLD);
    CHECK(!std::filesystem::exists(failed));
    CHECK(!std::filesystem::exists(failed + ".partial"));
  }
}

TEST_CASE("distributed outputs: a picture drawn by every rank is render_mesh's of the whole surface") {
  for (const auto& [shape_name, h, bbox] : kOutputCases) {
    CAPTURE(shape_name);
    const MovedSurface m = moved_surface(shape_name, h, bbox);
    const DistributedSurface& s = m.s;
    const SurfelMesh& serial = m.serial;
    // Values of both signs, so that the scale reads all three percentiles.
    const Eigen::VectorXd values = (serial.positions.col(0).array() * 0.7).sin() + 0.1;
    const Eigen::MatrixX3d& owned = m.owned;
    Eigen::VectorXd owned_values = owned_rows(s, values);
    const ScalarField field{"H", values, false};
    const FieldPercentiles expected = field_percentiles(field);
    const FieldPercentiles p = distributed_field_percentiles(s, "H", owned_values);
    CHECK(p.low == expected.low);
    CHECK(p.high == expected.high);
    CHECK(p.magnitude_high == expected.magnitude_high);

    RenderOptions options;
    options.width = 240;
    options.height = 200;
    const ColourScale scale = colour_scale(p, options);
    const Image coloured = distributed_render(s, owned, "H", owned_values, scale, options);
    const Image grey = distributed_render(s, owned, "", Eigen::VectorXd(), std::nullopt, options);
    if (world_rank() == 0) {
      const Image want = render_mesh(to_polygon_mesh(serial), &field, options);
      REQUIRE(coloured.width == want.width);
      CHECK(coloured.rgb == want.rgb);
      CHECK(grey.rgb == render_mesh(to_polygon_mesh(serial), nullptr, options).rgb);
      CHECK(grey.rgb != coloured.rgb);
    } else {
      CHECK(coloured.rgb.empty());
    }

    // A NaN on one rank: the same InputError everywhere.
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    if (world_rank() == ranks - 1 && s.num_owned > 0) owned_values[0] = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_AS(distributed_field_percentiles(s, "H", owned_values), InputError);
  }
}

TEST_CASE("distributed outputs: areas, the solution check, components and the quality against the shape") {
  // Two balls (two components) and goursat (one), with positions moved by up to 0.3 h * sqrt(3).
  for (const auto& [name, h, bbox, r] :
       {std::tuple{"(x^2+y^2+z^2-4)*((x-5)^2+y^2+z^2-4)", 0.25, 8.0, 1.0}, std::tuple{"goursat", 0.3, 10.0, 1.2}}) {
    CAPTURE(name);
    const MovedSurface m = moved_surface(name, h, bbox);
    const ImplicitShape& shape = m.shape;
    const DistributedSurface& s = m.s;
    const SurfelMesh &staircase = m.staircase, &serial = m.serial;
    const Eigen::MatrixX3d before = owned_rows(s, staircase.positions), after = m.owned;
    CHECK(distributed_components(s) == compute_mesh_info(serial).components);
    CHECK(distributed_surface_area(s, after) == doctest::Approx(surface_area(serial)).epsilon(1e-13));
    const SolutionCheck want = check_solution(staircase, serial.positions, 1e-9, "test");
    const SolutionCheck got = distributed_check_solution(s, before, after, 1e-9, "test");
    CHECK(got.area_ratio == doctest::Approx(want.area_ratio).epsilon(1e-13));
    CHECK(got.extent_ratio == want.extent_ratio);

    // The halo is read again from the shape; its width covers the balls about the moved vertices.
    const double displacement = 0.3 * h * std::sqrt(3.0);
    const DistributedHalo halo =
        distributed_halo(implicit_slab_source(shape, params(h, bbox)), s, quality_halo_columns(r, displacement, h));
    for (const auto& [mesh, owned, moved_by] :
         {std::tuple{&staircase, &before, 0.0},
          std::tuple{static_cast<const SurfelMesh*>(&serial), &after, displacement}}) {
      const SurfaceQuality expected = measure_against_shape(*mesh, shape, r);
      const SurfaceQuality q = distributed_measure_against_shape(s, halo, *owned, moved_by, shape, r);
      CHECK(q.distance_l1 == doctest::Approx(expected.distance_l1).epsilon(1e-12));
      CHECK(q.normal_angle_deg == doctest::Approx(expected.normal_angle_deg).epsilon(1e-12));
      CHECK(q.mean_curvature_error == doctest::Approx(expected.mean_curvature_error).epsilon(1e-10));
    }
    // A halo too narrow for the displacement is refused.
    CHECK_THROWS_AS(distributed_measure_against_shape(s, halo, after, 4.0 * displacement + 2.0 * h, shape, r),
                    InputError);
  }
}

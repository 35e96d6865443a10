// The distributed front end of the commands on volume files and with II normals
// (distributed/distributed_problem.hpp), under mpirun with 1, 2 and 4 ranks: every rank also
// builds the serial surface, normals and operators (test only) through load_surface and
// resolve_normals, as the serial front end does, and the distributed results must equal them.
#include <doctest/doctest.h>
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/discretizations/methods.hpp>
#include <corrlap/distributed/distributed_eigs.hpp>
#include <corrlap/distributed/distributed_poisson.hpp>
#include <corrlap/distributed/distributed_problem.hpp>
#include <corrlap/distributed/distributed_regularize_surface.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/pipeline/front_end.hpp>
#include <corrlap/pipeline/isotropic_resampling.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <corrlap/problems/problems.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>

using namespace corrlap;

namespace {

int world_rank() {
  ensure_petsc_runtime();  // MPI is started by the first distributed call; this may come before it
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

// A grey-level torus, 0 .. 255 falling off with the distance to the tube's core circle, so that
// the threshold decides the surface: about 4000 surfels at threshold 127.
VolumeData grey_torus(const Eigen::Vector3d& spacing) {
  VolumeData v;
  v.size = Eigen::Vector3i(44, 40, 18);
  v.bytes.assign(std::size_t(v.size.prod()), 0);
  const double R = 12.5, r = 5.2;
  for (int z = 0; z < v.size.z(); ++z)
    for (int y = 0; y < v.size.y(); ++y)
      for (int x = 0; x < v.size.x(); ++x) {
        const double px = x - 21.7, py = y - 19.4, pz = z - 8.6;
        const double d = std::hypot(std::hypot(px, py) - R, pz);
        const double value = std::clamp(255.0 * (1.0 - d / (2.0 * r)), 0.0, 255.0);
        v.bytes[std::size_t(x + v.size.x() * (y + v.size.y() * z))] = std::uint8_t(std::lround(value));
      }
  v.geometry.spacing = spacing;
  v.geometry.origin = Eigen::Vector3d(-3.0, 7.5, 1.25);
  return v;
}

// Written by rank 0 under a name every rank agrees on, visible to every rank on return.
std::string written(const VolumeData& v, const std::string& name) {
  ensure_petsc_runtime();
  long pid = long(::getpid());
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  const std::string path =
      (std::filesystem::temp_directory_path() / ("corrlap_front_end_volumes_" + std::to_string(pid) + "_" + name))
          .string();
  if (world_rank() == 0) write_volume_data(path, v);
  MPI_Barrier(MPI_COMM_WORLD);
  return path;
}

void remove_shared(const std::string& path) {
  MPI_Barrier(MPI_COMM_WORLD);
  if (world_rank() == 0) std::remove(path.c_str());
}

VolumeFileInput volume_input(const std::string& path, double threshold) {
  VolumeFileInput in;
  in.path = path;
  in.inside = InsideRule::above(threshold);
  return in;
}

NormalRequest ii_request(bool implicit_shape, std::optional<bool> shrink) {
  NormalRequest r;
  r.source = NormalSource::II;
  r.ii = default_ii_params(implicit_shape, {}, {}, shrink);
  return r;
}

// The serial front end's operators: load_surface, resolve_normals and the fem method.
struct Serial {
  LoadedSurface surface;
  Operators ops;
};
Serial serial_problem(const SurfaceInput& input, const NormalRequest& normals) {
  Serial s;
  s.surface = load_surface(input);
  const NormalFields n = resolve_normals(s.surface, NormalKind::Face, normals);
  s.ops = corrected_fem(s.surface.mesh, n.face);
  return s;
}

// The largest difference of the Poisson solutions (MUMPS on the distributed problem, CHOLMOD on the
// serial one), relative to the largest value of the serial solution, on every rank.
double poisson_difference(const DistributedProblem& p, const Serial& s) {
  const DistributedSurface& d = p.surface();
  const TestFunction& expx = test_function("expx");
  PetscLinearSolver solver;
  solver.configure(Config());  // the default: MUMPS's Cholesky
  const DistributedPoissonResult r = distributed_solve_poisson(d, p.fem(), expx, solver);
  auto cholmod = make_linear_solver("cholmod");
  const PoissonResult g = solve_poisson(s.ops, s.surface.mesh.positions, expx, *cholmod);
  double worst = 0.0;
  for (int v = 0; v < d.num_owned; ++v) worst = std::max(worst, std::abs(r.g[v] - g.g[d.vertex_ids[std::size_t(v)]]));
  MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  const Eigen::VectorXd whole = gather_on_rank0(d, r.g);
  if (d.rank == 0) CHECK((whole - g.g).cwiseAbs().maxCoeff() / g.g.cwiseAbs().maxCoeff() < 1e-10);
  return worst / g.g.cwiseAbs().maxCoeff();
}

void check_same_frame(const VoxelFrame& a, const VoxelFrame& b) {
  CHECK(a.h() == b.h());
  CHECK(a.shift() == b.shift());
  REQUIRE(a.geometry().has_value() == b.geometry().has_value());
  if (!a.geometry()) return;
  CHECK(a.geometry()->spacing == b.geometry()->spacing);
  CHECK(a.geometry()->origin == b.geometry()->origin);
  CHECK(a.geometry()->direction == b.geometry()->direction);
  CHECK(a.geometry()->space == b.geometry()->space);
}

}  // namespace

TEST_CASE("distributed problem of a volume file, II normals kept on thin parts: the serial Poisson solution") {
  // .npy and TIFF without geometry; NRRD, NIfTI and MetaImage with a physical spacing and origin.
  for (const std::string name : {"torus.npy", "torus.nrrd", "torus.nii.gz", "torus.mha", "torus.tif"}) {
    CAPTURE(name);
    const std::string path = written(grey_torus(Eigen::Vector3d::Constant(0.75)), name);
    const SurfaceInput input = volume_input(path, 127.0);
    const NormalRequest normals = ii_request(false, /*shrink=*/false);
    const DistributedProblem p(input, normals);
    const Serial s = serial_problem(input, normals);
    CHECK(p.normals() == NormalSource::II);
    CHECK(p.shape() == nullptr);
    CHECK(p.surface().num_vertices == s.surface.mesh.num_vertices());
    CHECK(p.surface().num_faces == s.surface.mesh.num_faces());
    check_same_frame(p.frame(), s.surface.frame);
    const double difference = poisson_difference(p, s);
    if (p.surface().rank == 0)
      MESSAGE(name << ": " << p.surface().num_faces << " faces, largest relative difference " << difference);
    CHECK(difference < 1e-10);
    remove_shared(path);
  }
}

TEST_CASE("distributed problem of a shape with II normals (kept on thin parts): the serial Poisson solution") {
  ImplicitShapeInput input;
  input.shape = "torus";
  input.digitization.h = 0.35;
  input.digitization.min_aabb = -10.0;
  input.digitization.max_aabb = 10.0;
  const NormalRequest normals = ii_request(true, /*shrink=*/false);
  const DistributedProblem p(input, normals);
  const Serial s = serial_problem(input, normals);
  CHECK(p.normals() == NormalSource::II);
  CHECK(p.shape() != nullptr);
  check_same_frame(p.frame(), s.surface.frame);
  const double difference = poisson_difference(p, s);
  if (p.surface().rank == 0) MESSAGE("torus, h = 0.35: largest relative difference " << difference);
  CHECK(difference < 1e-10);
}

TEST_CASE("distributed eigs of a volume file (II normals): the serial eigenvalues to 1e-8") {
  const std::string path = written(grey_torus(Eigen::Vector3d::Constant(0.75)), "torus_eigs.nrrd");
  const SurfaceInput input = volume_input(path, 127.0);
  const NormalRequest normals = ii_request(false, /*shrink=*/false);
  const DistributedProblem p(input, normals);
  const Serial s = serial_problem(input, normals);
  const int k = 12;
  auto spectra = make_eigen_solver(kDefaultEigenSolver, Config::from_key_values({"solver=cholmod"}));
  const EigenResult serial = spectra->solve(s.ops.L, s.ops.M, k);
  SlepcEigenSolver solver;
  solver.configure(Config());
  const EigenResult r = distributed_eigs(p.fem(), k, solver);
  REQUIRE(r.values.size() == k);
  const double difference = (r.values - serial.values).cwiseAbs().maxCoeff() / serial.values.cwiseAbs().maxCoeff();
  if (p.surface().rank == 0) MESSAGE("largest eigenvalue difference " << difference);
  CHECK(difference < 1e-8);
  remove_shared(path);
}

TEST_CASE("distributed problem of an anisotropic volume: load_surface's cubes, the serial Poisson solution") {
  // A coarse z (x not resampled), and a coarse x: each file column becomes three resampled ones,
  // so slabs cut between resampled columns that copy the same file column.
  const std::pair<Eigen::Vector3d, std::string> cases[] = {{Eigen::Vector3d(1.0, 1.0, 2.5), "torus_z.nrrd"},
                                                           {Eigen::Vector3d(3.0, 1.0, 1.0), "torus_x.mha"}};
  for (const auto& [spacing, name] : cases) {
    CAPTURE(name);
    const std::string path = written(grey_torus(spacing), name);
    const SurfaceInput input = volume_input(path, 127.0);
    for (const bool shrink : {false, true}) {
      CAPTURE(shrink);
      const NormalRequest normals = ii_request(false, shrink);
      std::string refused;
      const auto p = make_distributed_problem(input, normals, refused);
      CAPTURE(refused);
      REQUIRE(p);  // the distributed front end, no fallback
      const Serial s = serial_problem(input, normals);
      REQUIRE(s.surface.anisotropy > 1.0);
      CHECK(p->surface().num_vertices == s.surface.mesh.num_vertices());
      CHECK(p->surface().num_faces == s.surface.mesh.num_faces());
      check_same_frame(p->frame(), s.surface.frame);
      const double difference = poisson_difference(*p, s);
      if (p->surface().rank == 0)
        MESSAGE(name << std::string(shrink ? ", shrink" : ", keep") << ": " << p->surface().num_faces
                     << " faces, largest relative difference " << difference);
      CHECK(difference < 1e-10);
      // The ranks whose slab starts inside a file column: its first resampled column copies the
      // same file column as the previous rank's last one (3 x 1 x 1 on 4 ranks: one).
      const IsotropicResampling r = isotropic_resampling(Eigen::Vector3i(44, 40, 18), grey_torus(spacing).geometry, {});
      const int k = p->surface().slab.first - r.lower().x() - 1;  // its first resampled index
      int shared = k > 0 && k < r.size.x() && r.source[0][std::size_t(k)] == r.source[0][std::size_t(k - 1)];
      MPI_Allreduce(MPI_IN_PLACE, &shared, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
      if (p->surface().rank == 0) MESSAGE(name << ": " << shared << " slab cuts inside a file column");
      if (spacing.x() > 1.0 && p->surface().ranks == 4) CHECK(shared == 1);
    }
    remove_shared(path);
  }
}

TEST_CASE("distributed problem with the default II (smaller balls on thin parts): the serial result") {
  const std::string path = written(grey_torus(Eigen::Vector3d::Constant(0.75)), "torus_shrink.npy");
  const SurfaceInput input = volume_input(path, 127.0);
  NormalRequest normals;  // auto on a volume: II, with the voxel defaults
  normals.ii = default_ii_params(false);
  REQUIRE(normals.ii->shrink_on_thin_parts);
  std::string refused;
  const auto p = make_distributed_problem(input, normals, refused);
  CAPTURE(refused);
  REQUIRE(p);
  const double difference = poisson_difference(*p, serial_problem(input, normals));
  if (world_rank() == 0) MESSAGE("shrink distributed: largest relative difference " << difference);
  CHECK(difference < 1e-10);
  remove_shared(path);
}

TEST_CASE("distributed problem: inputs it does not compute as the serial front end are refused on every rank") {
  // True normals need a shape; trivial normals and given normals are not distributed.
  const std::string iso = written(grey_torus(Eigen::Vector3d::Constant(1.0)), "torus_iso.npy");
  std::string refused;
  NormalRequest normals;
  normals.source = NormalSource::True;
  CHECK(make_distributed_problem(volume_input(iso, 127.0), normals, refused) == nullptr);
  normals.source = NormalSource::Trivial;
  CHECK(make_distributed_problem(volume_input(iso, 127.0), normals, refused) == nullptr);
  normals.source = NormalSource::II;
  normals.face_normals_file = "normals.txt";
  CHECK(make_distributed_problem(volume_input(iso, 127.0), normals, refused) == nullptr);
  remove_shared(iso);
}

TEST_CASE("choose_front_end: volume files and II normals take the distributed front end") {
  FrontEndRequest solve;
  solve.volume_file = true;
  solve.solver = "petsc";
  FrontEndRequest eigs = solve;
  eigs.task = FrontEndRequest::Task::Eigen;
  eigs.solver = "slepc";
  auto with = [](FrontEndRequest r, auto change) {
    change(r);
    return choose_front_end(r);
  };
  for (const FrontEndRequest& r : {solve, eigs}) {
    CHECK(choose_front_end(r) == FrontEnd::Distributed);  // auto: II on a volume
    CHECK(with(r, [](FrontEndRequest& q) { q.normals = "ii"; }) == FrontEnd::Distributed);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals = "true"; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals = "trivial"; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals = "convolved"; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals_from_file = true; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.method = "interpolated"; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.volume_file = false; }) == FrontEnd::Serial);  // a mesh file
    // A shape with II or true normals.
    CHECK(with(r, [](FrontEndRequest& q) {
            q.volume_file = false;
            q.implicit_shape = true;
            q.normals = "ii";
          }) == FrontEnd::Distributed);
  }
  CHECK(with(solve, [](FrontEndRequest& q) { q.task = FrontEndRequest::Task::Heat; }) == FrontEnd::Serial);
  CHECK(with(solve, [](FrontEndRequest& q) { q.rhs_from_test_function = false; }) == FrontEnd::Serial);
  CHECK(with(solve, [](FrontEndRequest& q) { q.solver = "cholmod"; }) == FrontEnd::Serial);
  // regularize: the petsc solver, without what only the serial regularization does.
  FrontEndRequest regularize = solve;
  regularize.task = FrontEndRequest::Task::Regularize;
  CHECK(choose_front_end(regularize) == FrontEnd::Distributed);
  CHECK(with(regularize, [](FrontEndRequest& q) { q.solver = "cholmod"; }) == FrontEnd::Serial);
  CHECK(with(regularize, [](FrontEndRequest& q) { q.serial_only_regularization = true; }) == FrontEnd::Serial);
  CHECK(with(regularize, [](FrontEndRequest& q) { q.method = "polydec"; }) == FrontEnd::Serial);
  CHECK(with(regularize, [](FrontEndRequest& q) {
          q.volume_file = false;
          q.implicit_shape = true;
          q.normals = "true";
        }) == FrontEnd::Distributed);
}

TEST_CASE("distributed regularization of a shape and of a volume equals the serial regularize_surface") {
  // The command's defaults (automatic alpha0, sites of §8.4), solved to rounding on both sides: the
  // serial preconditioned CG with CHOLMOD, MUMPS and CG over the ranks here.
  RegularizationOptions o;
  o.solve_accuracy = 0.0;
  o.solver.set("solver", "petsc");
  RegularizationOptions serial_options = o;
  serial_options.solver = Config();  // CHOLMOD
  struct Case {
    std::string name;
    SurfaceInput input;
    NormalRequest normals;
    double alpha0 = 10.0;  // 1: the bias is above the limit, so alpha0 is raised (several trials)
  };
  ImplicitShapeInput torus;
  torus.shape = "torus";
  torus.digitization.h = 0.35;
  torus.digitization.min_aabb = -10.0;
  torus.digitization.max_aabb = 10.0;
  NormalRequest true_normals;
  true_normals.source = NormalSource::True;
  const std::string path = written(grey_torus(Eigen::Vector3d::Ones()), "regularize.nrrd");
  for (const Case& c :
       {Case{"torus shape, true normals", torus, true_normals},
        Case{"grey torus volume, II normals", volume_input(path, 127.0), ii_request(false, {})},
        Case{"grey torus volume, II normals, alpha0 from 1", volume_input(path, 127.0), ii_request(false, {}), 1.0}}) {
    CAPTURE(c.name);
    o.alpha0 = serial_options.alpha0 = c.alpha0;
    const DistributedProblem p(c.input, c.normals);
    const LoadedSurface serial = load_surface(c.input);
    NormalFields n = resolve_normals(serial, NormalKind::Vertex, c.normals);
    if (!n.has_face()) n.face = resolve_normals(serial, NormalKind::Face, c.normals).face;
    const RegularizedSurface expected = regularize_surface(serial, n, serial_options);

    PetscLinearSolver solver;
    solver.configure(Config());  // MUMPS's Cholesky
    const DistributedRegularizedSurface r = distributed_regularize_surface(p, o, voxels_from_file(serial), solver);
    CHECK(r.size == expected.size);
    CHECK(r.curvature_radius == expected.curvature_radius);
    // A raised alpha0 follows from the bias, which agrees to rounding: so does alpha0.
    CHECK(std::abs(r.alpha0 - expected.alpha0) <= 1e-9 * expected.alpha0);
    REQUIRE(r.alpha0_trials.size() == expected.alpha0_trials.size());
    if (c.alpha0 == 1.0) CHECK(r.alpha0_trials.size() > 1);
    for (std::size_t t = 0; t < r.alpha0_trials.size(); ++t) {
      CHECK(std::abs(r.alpha0_trials[t].alpha0 - expected.alpha0_trials[t].alpha0) <=
            1e-9 * expected.alpha0_trials[t].alpha0);
      CHECK(std::abs(r.alpha0_trials[t].bias - expected.alpha0_trials[t].bias) <=
            1e-9 * expected.alpha0_trials[t].bias);
    }
    const DistributedSurface& d = p.surface();
    double worst_H = 0.0, worst_p = 0.0;
    for (int v = 0; v < d.num_owned; ++v) {
      const Eigen::Index id = d.vertex_ids[std::size_t(v)];
      worst_H = std::max(worst_H, std::abs(r.H[v] - expected.H[id]));
      worst_p = std::max(worst_p, (r.positions.row(v) - expected.mesh.positions.row(id)).norm());
    }
    MPI_Allreduce(MPI_IN_PLACE, &worst_H, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &worst_p, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    // H to rounding (sums in another order); positions to 1e-8 of the object size (issue's bound;
    // both solves stop at a relative residual of 1e-10).
    CHECK(worst_H <= 1e-12 * expected.H.cwiseAbs().maxCoeff());
    CHECK(worst_p <= 1e-8 * expected.size);
    if (d.rank == 0)
      MESSAGE(c.name << ": alpha0 " << r.alpha0 << " after " << r.alpha0_trials.size() << " trials, "
                     << r.solve_iterations << " CG iterations, worst |p' - serial| / size " << worst_p / expected.size);
  }
  // What is not distributed is refused alike on every rank.
  o.alpha0 = 10.0;
  const DistributedProblem p(torus, true_normals);
  PetscLinearSolver solver;
  solver.configure(Config());
  RegularizationOptions other = o;
  other.method = "polydec";
  CHECK_THROWS_AS((void)distributed_regularize_surface(p, other, false, solver), InputError);
  other = o;
  other.k1_edit.kind = PrincipalCurvatureEdit::Kind::Scale;
  other.k1_edit.value = 2.0;
  CHECK_THROWS_AS((void)distributed_regularize_surface(p, other, false, solver), InputError);
  remove_shared(path);
}

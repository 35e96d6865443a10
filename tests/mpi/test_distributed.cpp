// The distributed front end (distributed/) under mpirun with 1, 2 and 4 ranks: every rank builds the
// serial surface and operators too (test only) and checks its share of the distributed ones against
// them: the same faces and vertices with the same ids, the same L and M entries, the same Poisson
// solution.
#include <doctest/doctest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/discretizations/methods.hpp>
#include <corrlap/distributed/distributed_eigs.hpp>
#include <corrlap/distributed/distributed_fem.hpp>
#include <corrlap/distributed/distributed_poisson.hpp>
#include <corrlap/distributed/distributed_regularization.hpp>
#include <corrlap/distributed/distributed_surface.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/pipeline/front_end.hpp>
#include <corrlap/problems/problems.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <string>
#include <vector>

using namespace corrlap;

namespace {

struct Case {
  std::string shape;
  double h, bbox;
};
// sphere1 at three steps and in the CLI's default box; the torus (genus 1) and goursat (non-convex)
// at two steps.
const std::vector<Case> kCases = {{"sphere1", 0.2, 2.0},  {"sphere1", 0.1, 2.0},   {"sphere1", 0.07, 2.0},
                                  {"torus", 0.5, 10.0},   {"torus", 0.35, 10.0},   {"goursat", 0.5, 10.0},
                                  {"goursat", 0.3, 10.0}, {"sphere1", 0.025, 10.0}};

DigitizationParams params_of(const Case& c) {
  DigitizationParams p;
  p.h = c.h;
  p.min_aabb = -c.bbox;
  p.max_aabb = c.bbox;
  return p;
}

std::int64_t sum_over_ranks(std::int64_t x) {
  MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  return x;
}

// Serial id of every matrix row: the ranks' owned vertices, rank after rank (test only: #V values).
std::vector<std::int64_t> serial_of_rows(const DistributedSurface& d) {
  std::vector<int> counts(std::size_t(d.ranks)), offsets(std::size_t(d.ranks), 0);
  MPI_Allgather(&d.num_owned, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  for (int r = 1; r < d.ranks; ++r) offsets[std::size_t(r)] = offsets[std::size_t(r - 1)] + counts[std::size_t(r - 1)];
  std::vector<std::int64_t> all(std::size_t(d.num_vertices));
  MPI_Allgatherv(d.vertex_ids.data(), d.num_owned, MPI_INT64_T, all.data(), counts.data(), offsets.data(), MPI_INT64_T,
                 MPI_COMM_WORLD);
  return all;
}

}  // namespace

TEST_CASE("distributed surface: each rank digitizes only its slab and one column each side") {
  for (const Case& c : kCases) {
    CAPTURE(c.shape);
    CAPTURE(c.h);
    const DistributedSurface d = distributed_surface(make_implicit_shape(c.shape), params_of(c));
    Eigen::Vector3i lower, upper;
    digitization_box(params_of(c), lower, upper);
    const int n = upper.x() - lower.x() + 1;
    // Slabs of n / P columns (floor or ceil), in rank order, covering the box once.
    CHECK(d.slab.columns() >= n / d.ranks);
    CHECK(d.slab.columns() <= n / d.ranks + 1);
    CHECK(sum_over_ranks(d.slab.columns()) == n);
    CHECK(d.grid_lower.x() == std::max(lower.x(), d.slab.first - 1));
    CHECK(d.grid_upper.x() == std::min(upper.x(), d.slab.last + 1));
    CHECK(d.grid_lower.y() == lower.y());
    CHECK(d.grid_upper.z() == upper.z());
    if (d.ranks > 1) CHECK(d.grid_upper.x() - d.grid_lower.x() + 1 < n);
  }
}

TEST_CASE("distributed surface: the faces and vertices of extract_surface, with its ids") {
  for (const Case& c : kCases) {
    CAPTURE(c.shape);
    CAPTURE(c.h);
    const ImplicitShape shape = make_implicit_shape(c.shape);
    const DistributedSurface d = distributed_surface(shape, params_of(c));
    const SurfelMesh serial = extract_surface(digitize(shape, params_of(c)));
    REQUIRE(d.num_faces == serial.num_faces());
    REQUIRE(d.num_vertices == serial.num_vertices());
    // Every serial face once over the ranks, every vertex owned once.
    std::vector<std::int64_t> face_seen(std::size_t(d.num_faces), 0), vertex_seen(std::size_t(d.num_vertices), 0);
    const SurfelMesh& m = d.mesh;
    bool same = true;
    for (int f = 0; f < m.num_faces(); ++f) {
      const std::int64_t id = d.face_ids[std::size_t(f)];
      ++face_seen[std::size_t(id)];
      const Surfel& a = m.surfels[std::size_t(f)];
      const Surfel& b = serial.surfels[std::size_t(id)];
      same = same && a.lower_voxel == b.lower_voxel && a.axis == b.axis && a.outward == b.outward;
      for (int k = 0; k < 4; ++k) same = same && serial.faces(id, k) == d.vertex_ids[std::size_t(m.faces(f, k))];
    }
    CHECK(same);
    bool positions = true, rows = true;
    for (int v = 0; v < m.num_vertices(); ++v) {
      // Bit for bit: the same formula of the same pointel.
      positions =
          positions && (m.positions.row(v).array() == serial.positions.row(d.vertex_ids[std::size_t(v)]).array()).all();
      if (v < d.num_owned) {
        ++vertex_seen[std::size_t(d.vertex_ids[std::size_t(v)])];
        rows = rows && d.rows[std::size_t(v)] == d.row_begin + v;
        if (v > 0) rows = rows && d.vertex_ids[std::size_t(v)] > d.vertex_ids[std::size_t(v - 1)];
      }
    }
    CHECK(positions);
    CHECK(rows);
    MPI_Allreduce(MPI_IN_PLACE, face_seen.data(), int(face_seen.size()), MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, vertex_seen.data(), int(vertex_seen.size()), MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    CHECK(std::all_of(face_seen.begin(), face_seen.end(), [](std::int64_t k) { return k == 1; }));
    CHECK(std::all_of(vertex_seen.begin(), vertex_seen.end(), [](std::int64_t k) { return k == 1; }));
    // The rows of the matrices: the ranks' owned vertices rank after rank.
    CHECK(sum_over_ranks(d.num_owned) == d.num_vertices);
  }
}

TEST_CASE("distributed fem: L and M equal the serial corrected FEM entry by entry") {
  for (const Case& c : kCases) {
    CAPTURE(c.shape);
    CAPTURE(c.h);
    const ImplicitShape shape = make_implicit_shape(c.shape);
    const DistributedSurface d = distributed_surface(shape, params_of(c));
    const DistributedFem fem(d, true_face_normals(shape, d.mesh));
    const SurfelMesh mesh = extract_surface(digitize(shape, params_of(c)));
    const Operators ops = corrected_fem(mesh, true_face_normals(shape, mesh));
    const std::vector<std::int64_t> serial = serial_of_rows(d);
    for (const auto which : {DistributedFem::Which::L, DistributedFem::Which::M}) {
      const Eigen::SparseMatrix<double>& A = which == DistributedFem::Which::L ? ops.L : ops.M;
      const Eigen::SparseMatrix<double, Eigen::RowMajor> R = A;
      // An entry sums the same face terms (at most 4) as the serial one in another order: they
      // differ by a few roundings of the largest term, below 1e-14 of the row's largest entry.
      double worst = 0.0;
      std::int64_t entries = 0, rows_with_other_count = 0;
      std::vector<int> per_row(std::size_t(d.num_owned), 0);
      for (const auto& e : fem.owned_entries(which)) {
        const std::int64_t i = serial[std::size_t(e.row)], j = serial[std::size_t(e.column)];
        const double scale = Eigen::VectorXd(R.row(Eigen::Index(i)).transpose()).cwiseAbs().maxCoeff();
        worst = std::max(worst, std::abs(e.value - R.coeff(Eigen::Index(i), Eigen::Index(j))) / scale);
        ++per_row[std::size_t(e.row - d.row_begin)];
        ++entries;
      }
      for (int v = 0; v < d.num_owned; ++v)
        if (per_row[std::size_t(v)] != R.row(Eigen::Index(d.vertex_ids[std::size_t(v)])).nonZeros())
          ++rows_with_other_count;
      CHECK(worst < 1e-14);
      CHECK(rows_with_other_count == 0);
      CHECK(sum_over_ranks(entries) == A.nonZeros());
    }
  }
}

TEST_CASE("distributed Poisson solve equals CHOLMOD's serial solve_poisson to 1e-10") {
  for (const Case& c : {kCases[1], kCases[4], kCases[7]}) {
    CAPTURE(c.shape);
    const ImplicitShape shape = make_implicit_shape(c.shape);
    const DistributedSurface d = distributed_surface(shape, params_of(c));
    const DistributedFem fem(d, true_face_normals(shape, d.mesh));
    const TestFunction& expx = test_function("expx");
    PetscLinearSolver solver;
    solver.configure(Config());  // the default: MUMPS's Cholesky
    const DistributedPoissonResult r = distributed_solve_poisson(d, fem, expx, solver);
    CHECK(r.report.ordering == "mumps");
    CHECK(r.report.message == "KSP CONVERGED_ITS");
    const SurfelMesh mesh = extract_surface(digitize(shape, params_of(c)));
    const Operators ops = corrected_fem(mesh, true_face_normals(shape, mesh));
    auto cholmod = make_linear_solver("cholmod");
    const PoissonResult s = solve_poisson(ops, mesh.positions, expx, *cholmod);
    double worst = 0.0;
    for (int v = 0; v < d.num_owned; ++v) worst = std::max(worst, std::abs(r.g[v] - s.g[d.vertex_ids[std::size_t(v)]]));
    MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    CHECK(worst / s.g.cwiseAbs().maxCoeff() < 1e-10);
    CHECK(std::abs(r.residual - s.residual) < 1e-10);
    CHECK(std::abs(r.errors.l2 - s.errors.l2) < 1e-10 * s.errors.l2 + 1e-14);
    const Eigen::VectorXd whole = gather_on_rank0(d, r.g);
    if (d.rank == 0) CHECK((whole - s.g).cwiseAbs().maxCoeff() / s.g.cwiseAbs().maxCoeff() < 1e-10);
  }
}

TEST_CASE("distributed regularization solve equals the serial preconditioned one to 1e-8 of the object size") {
  // The normal equations of docs/math.md §9.2 with true normals and a smooth H (any H serves: the
  // solve is what is compared), alpha = 10 / h^2 as the regularization's default.
  for (const Case& c : {kCases[1], kCases[4]}) {
    CAPTURE(c.shape);
    const ImplicitShape shape = make_implicit_shape(c.shape);
    const DistributedSurface d = distributed_surface(shape, params_of(c));
    const DistributedFem fem(d, true_face_normals(shape, d.mesh));
    const auto H_of = [](const Eigen::MatrixX3d& x) -> Eigen::VectorXd { return 1.0 + 0.1 * x.col(0).array(); };
    const Eigen::MatrixX3d p = d.mesh.positions.topRows(d.num_owned);
    const Eigen::MatrixX3d n = true_vertex_normals(shape, d.mesh).topRows(d.num_owned);
    const double alpha = regularization_alpha(c.h);
    PetscLinearSolver solver;
    solver.configure(Config());  // MUMPS's Cholesky
    const DistributedRegularization r = distributed_regularize_positions(d, fem, p, n, H_of(p), alpha, solver);
    CHECK(r.residual <= 1e-10);
    CHECK(r.iterations <= 60);

    const SurfelMesh mesh = extract_surface(digitize(shape, params_of(c)));
    const Operators ops = corrected_fem(mesh, true_face_normals(shape, mesh));
    auto cholmod = make_linear_solver("cholmod");
    const Eigen::MatrixX3d serial = regularize_positions_preconditioned(
        ops.L, ops.M, mesh.positions, true_vertex_normals(shape, mesh), H_of(mesh.positions), alpha, *cholmod);
    const double size = mesh.positions.cwiseAbs().maxCoeff();
    double worst = 0.0;
    for (int v = 0; v < d.num_owned; ++v)
      worst = std::max(worst, (r.positions.row(v) - serial.row(d.vertex_ids[std::size_t(v)])).norm());
    MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    CHECK(worst <= 1e-8 * size);
    if (d.rank == 0) MESSAGE(c.shape << ": " << r.iterations << " CG iterations, worst difference " << worst / size);

    // Started from its own result or from the staircase: the same solution.
    for (const Eigen::MatrixX3d* start : {&r.positions, &p}) {
      const DistributedRegularization again =
          distributed_regularize_positions(d, fem, p, n, H_of(p), alpha, solver, 0.0, start);
      double moved = again.positions.rows() > 0 ? (again.positions - r.positions).cwiseAbs().maxCoeff() : 0.0;
      MPI_Allreduce(MPI_IN_PLACE, &moved, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
      CHECK(moved <= 1e-8 * size);
    }
    const Eigen::MatrixX3d short_start = p.topRows(d.num_owned > 0 ? d.num_owned - 1 : 0);
    CHECK_THROWS_AS((void)distributed_regularize_positions(d, fem, p, n, H_of(p), alpha, solver, 0.0, &short_start),
                    InputError);

    // To an accuracy: the bound reached, and the error within it (RMS over the area, as the bound).
    const double accuracy = 1e-3 * c.h;
    const DistributedRegularization loose =
        distributed_regularize_positions(d, fem, p, n, H_of(p), alpha, solver, accuracy);
    CHECK(loose.error_bound <= accuracy);
    CHECK(loose.iterations < r.iterations);
    const Eigen::VectorXd mass = (ops.M * Eigen::VectorXd::Ones(mesh.num_vertices()));
    Eigen::Vector4d sums = Eigen::Vector4d::Zero();  // M_l-weighted squared errors per coordinate, area
    for (int v = 0; v < d.num_owned; ++v) {
      const Eigen::Index id = d.vertex_ids[std::size_t(v)];
      sums.head<3>() += mass[id] * (loose.positions.row(v) - serial.row(id)).cwiseAbs2().transpose();
      sums[3] += mass[id];
    }
    MPI_Allreduce(MPI_IN_PLACE, sums.data(), 4, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    CHECK(std::sqrt(sums.head<3>().maxCoeff() / sums[3]) <= accuracy);

    // The automatic alpha0's bias of the result against the staircase (docs/math.md §9.4).
    // Of the serial result, so that only the bias is compared.
    Eigen::VectorXd owned_mass(d.num_owned);
    Eigen::MatrixX3d owned_serial(d.num_owned, 3);
    for (int v = 0; v < d.num_owned; ++v) {
      owned_mass[v] = mass[d.vertex_ids[std::size_t(v)]];
      owned_serial.row(v) = serial.row(d.vertex_ids[std::size_t(v)]);
    }
    const double bias = distributed_attachment_bias(d, p, owned_serial, n, owned_mass, c.h);
    const double serial_bias =
        attachment_bias(mesh.faces, mesh.positions, serial, true_vertex_normals(shape, mesh), mass, c.h);
    // The same sums in another order, 16 rounds of averaging: 1e-12 relative.
    CHECK(serial_bias > 0.0);
    CHECK(std::abs(bias - serial_bias) <= 1e-12 * serial_bias);
    CHECK_THROWS_AS((void)distributed_attachment_bias(d, p, r.positions, n, owned_mass, 0.0), InputError);

    CHECK_THROWS_AS((void)distributed_regularize_positions(d, fem, p, n, H_of(p), -1.0, solver), InputError);
    Eigen::VectorXd bad = H_of(p);
    for (int v = 0; v < d.num_owned; ++v)  // on one rank only: every rank throws
      if (d.vertex_ids[std::size_t(v)] == 0) bad[v] = std::nan("");
    CHECK_THROWS_AS((void)distributed_regularize_positions(d, fem, p, n, bad, alpha, solver), InputError);
  }
}

namespace {

// The 2-norm condition number of the distributed pinned system (docs/math.md §10.4): up to a
// permutation, the serial pinned system (without the pinned row and column) plus the pinned row's
// 1 on the diagonal, so its eigenvalues are the serial ones and 1. The serial extreme eigenvalues
// are Rayleigh quotients of power iterations: on A for the largest, on A^{-1} (CHOLMOD) for the
// smallest. Both quotients lie inside [lambda_min, lambda_max], so the estimate is at most the true
// condition number; 300 steps leave it within a few percent on these sizes (the estimate moves less
// than that over the last 100 steps).
double condition_number(const Eigen::SparseMatrix<double>& A) {
  auto cholmod = make_linear_solver("cholmod");
  cholmod->compute(A);
  Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(A.rows(), 1.0, 2.0), w = u;
  double largest = 0.0, smallest = 0.0;
  for (int step = 0; step < 300; ++step) {
    u = (A * u).normalized();
    w = cholmod->solve(w).col(0).normalized();
  }
  largest = std::max(u.dot(A * u), 1.0);
  smallest = std::min(w.dot(A * w), 1.0);
  return largest / smallest;
}

double global_norm2(const Eigen::VectorXd& owned) {
  double squares = owned.squaredNorm();
  MPI_Allreduce(MPI_IN_PLACE, &squares, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return std::sqrt(squares);
}

int ranks_that(bool yes) {
  int count = yes ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &count, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  return count;
}

}  // namespace

TEST_CASE("distributed Poisson with CG + GAMG and CG + hypre equals CHOLMOD within cond(A) times the true residual") {
  const double rtol = 1e-10;
  for (const Case& c : {kCases[1], kCases[4]}) {
    CAPTURE(c.shape);
    CAPTURE(c.h);
    const ImplicitShape shape = make_implicit_shape(c.shape);
    const DistributedSurface d = distributed_surface(shape, params_of(c));
    const DistributedFem fem(d, true_face_normals(shape, d.mesh));
    const TestFunction& expx = test_function("expx");
    const SurfelMesh mesh = extract_surface(digitize(shape, params_of(c)));
    const Operators ops = corrected_fem(mesh, true_face_normals(shape, mesh));
    auto cholmod = make_linear_solver("cholmod");
    const PoissonResult s = solve_poisson(ops, mesh.positions, expx, *cholmod);
    const double kappa = condition_number(pinned_system(ops.L));
    if (d.rank == 0) MESSAGE(c.shape << " h = " << c.h << ": cond_2 of the pinned system " << kappa);
    for (const std::string pc : {"pc_type=gamg", "pc_type=hypre"}) {
      CAPTURE(pc);
      PetscLinearSolver solver;
      solver.configure(Config::from_key_values({"ksp_type=cg", pc, "rtol=1e-10"}));
      const DistributedPoissonResult r = distributed_solve_poisson(d, fem, expx, solver);
      Eigen::VectorXd serial(d.num_owned);
      for (int v = 0; v < d.num_owned; ++v) serial[v] = s.g[d.vertex_ids[std::size_t(v)]];
      // |g - g*| / |g*| <= cond_2(A) |A g - b| / |b| for the pinned system A g = b, and the backend
      // accepts cg's solution only with a true relative residual <= 10 rtol. CHOLMOD's own error
      // (cond_2 times a few roundings) is far below; the factor 2 covers the condition number
      // estimate being a few percent low.
      const double error = global_norm2(r.g - serial) / global_norm2(serial);
      if (d.rank == 0)
        MESSAGE(pc << ": relative error " << error << ", true residual " << r.report.residual << ", "
                   << r.report.iterations << " iterations, bound " << 2.0 * kappa * r.report.residual);
      CHECK(r.report.residual <= 10.0 * rtol);
      CHECK(error <= 2.0 * kappa * std::max(r.report.residual, 1e-15));
      CHECK(error <= 2.0 * kappa * 10.0 * rtol);
      CHECK(r.report.iterations > 1);
      CHECK(r.report.message == "KSP CONVERGED_RTOL");
    }
  }
}

TEST_CASE("distributed Poisson: divergence and bad options fail on every rank with the cause") {
  const Case c = kCases[1];
  const ImplicitShape shape = make_implicit_shape(c.shape);
  const DistributedSurface d = distributed_surface(shape, params_of(c));
  const DistributedFem fem(d, true_face_normals(shape, d.mesh));
  const TestFunction& expx = test_function("expx");
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  // Unpreconditioned CG needs far more than 5 iterations: PETSc's reason, on every rank (the
  // Allreduce below is reached by all of them, so none hangs in the solve).
  {
    PetscLinearSolver solver;
    solver.configure(Config::from_key_values({"ksp_type=cg", "pc_type=none", "max_it=5"}));
    std::string message;
    try {
      distributed_solve_poisson(d, fem, expx, solver);
    } catch (const SolverError& e) {
      message = e.what();
    }
    CHECK(message.find("DIVERGED_ITS after 5 iterations") != std::string::npos);
    CHECK(ranks_that(message.find("DIVERGED_ITS") != std::string::npos) == size);
    CHECK(solver.info().status == SolverStatus::NoConvergence);
  }
  // A pass-through value PETSc refuses, when the KSP is set up on the distributed matrix.
  {
    PetscLinearSolver solver;
    solver.configure(Config::from_key_values({"ksp_type=cg", "pc_type=gamg", "pc_gamg_type=nonsense"}));
    std::string message;
    try {
      distributed_solve_poisson(d, fem, expx, solver);
    } catch (const InputError& e) {
      message = e.what();
    }
    CHECK(ranks_that(message.find("nonsense") != std::string::npos) == size);
  }
  // A preconditioner the backend does not offer, before anything is solved.
  {
    PetscLinearSolver solver;
    std::string message;
    try {
      solver.configure(Config::from_key_values({"pc_type=ilu0"}));
    } catch (const InputError& e) {
      message = e.what();
    }
    CHECK(ranks_that(message.find("cholesky, gamg, hypre") != std::string::npos) == size);
  }
  // The same solver object still solves after a failure.
  PetscLinearSolver solver;
  solver.configure(Config::from_key_values({"ksp_type=cg", "pc_type=gamg", "rtol=1e-8"}));
  CHECK(distributed_solve_poisson(d, fem, expx, solver).report.residual <= 1e-7);
}

TEST_CASE("choose_front_end: the distributed front end exactly for the inputs it computes") {
  FrontEndRequest solve;
  solve.implicit_shape = true;
  solve.solver = "petsc";
  CHECK(choose_front_end(solve) == FrontEnd::Distributed);
  FrontEndRequest eigs = solve;
  eigs.task = FrontEndRequest::Task::Eigen;
  eigs.solver = "slepc";
  CHECK(choose_front_end(eigs) == FrontEnd::Distributed);
  CHECK(to_string(choose_front_end(eigs)) == "distributed");
  // Each departure from that scope takes the serial front end.
  auto with = [](FrontEndRequest r, auto change) {
    change(r);
    return choose_front_end(r);
  };
  for (const FrontEndRequest& r : {solve, eigs}) {
    CHECK(with(r, [](FrontEndRequest& q) { q.implicit_shape = false; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals = "ii"; }) == FrontEnd::Distributed);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals = "trivial"; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals = "true"; }) == FrontEnd::Distributed);
    CHECK(with(r, [](FrontEndRequest& q) { q.normals_from_file = true; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.method = "interpolated"; }) == FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.method_parameters = Config::from_key_values({"mass=lumped"}); }) ==
          FrontEnd::Serial);
    CHECK(with(r, [](FrontEndRequest& q) { q.solver = "cholmod"; }) == FrontEnd::Serial);
  }
  CHECK(with(solve, [](FrontEndRequest& q) { q.task = FrontEndRequest::Task::Heat; }) == FrontEnd::Serial);
  CHECK(with(solve, [](FrontEndRequest& q) { q.rhs_from_test_function = false; }) == FrontEnd::Serial);
  // eigs --solver petsc: the linear solver of the serial Spectra shift-invert, not slepc.
  CHECK(with(eigs, [](FrontEndRequest& q) { q.solver = "petsc"; }) == FrontEnd::Serial);
}

TEST_CASE("distributed eigs (slepc on the distributed L and M) equal the serial eigenvalues to 1e-8") {
  const int k = 12;
  for (const Case& c : {kCases[1], kCases[4]}) {
    CAPTURE(c.shape);
    CAPTURE(c.h);
    const ImplicitShape shape = make_implicit_shape(c.shape);
    const DistributedSurface d = distributed_surface(shape, params_of(c));
    const DistributedFem fem(d, true_face_normals(shape, d.mesh));
    const SurfelMesh mesh = extract_surface(digitize(shape, params_of(c)));
    const Operators ops = corrected_fem(mesh, true_face_normals(shape, mesh));
    // The serial reference: Spectra's shift-invert with CHOLMOD (`corrlap eigs --solver cholmod`).
    auto spectra = make_eigen_solver(kDefaultEigenSolver, Config::from_key_values({"solver=cholmod"}));
    const EigenResult serial = spectra->solve(ops.L, ops.M, k);
    SlepcEigenSolver solver;
    solver.configure(Config());  // shift-invert with MUMPS's Cholesky
    const EigenResult r = distributed_eigs(fem, k, solver);
    REQUIRE(r.values.size() == k);
    REQUIRE(r.vectors.rows() == d.num_owned);
    REQUIRE(r.vectors.cols() == k);
    // Relative to the largest value, as tests/mpi/cli_petsc.sh compares the CLI's.
    const double difference = (r.values - serial.values).cwiseAbs().maxCoeff() / serial.values.cwiseAbs().maxCoeff();
    if (d.rank == 0) MESSAGE("largest eigenvalue difference " << difference);
    CHECK(difference < 1e-8);
    // Each gathered vector is an eigenvector of the serial pencil, M-normalized: |L u + mu M u|
    // small against |L| |u| (slepc's tolerance 1e-10 is on the relative residual of the pair).
    for (int i = 0; i < k; ++i) {
      const Eigen::VectorXd u = gather_on_rank0(d, r.vectors.col(i));
      if (d.rank != 0) continue;
      const double residual = (ops.L * u + r.values[i] * (ops.M * u)).norm() / (ops.L.cwiseAbs() * u.cwiseAbs()).norm();
      CHECK(residual < 1e-6);
      CHECK(std::abs(u.dot(ops.M * u) - 1.0) < 1e-10);
    }
  }
}

TEST_CASE("distributed eigs with slepc's LOBPCG (GAMG) finds the serial eigenvalues") {
  // As the serial front end's LOBPCG test (test_petsc.cpp): the sphere's closed clusters 1 + 3 + 5,
  // tolerance 1e-9, values to 1e-6 of the largest.
  const int k = 9;
  const Case c = kCases[1];
  const ImplicitShape shape = make_implicit_shape(c.shape);
  const DistributedSurface d = distributed_surface(shape, params_of(c));
  const DistributedFem fem(d, true_face_normals(shape, d.mesh));
  const SurfelMesh mesh = extract_surface(digitize(shape, params_of(c)));
  const Operators ops = corrected_fem(mesh, true_face_normals(shape, mesh));
  const EigenResult serial = make_eigen_solver(kDefaultEigenSolver)->solve(ops.L, ops.M, k);
  SlepcEigenSolver solver;
  solver.configure(Config::from_key_values({"method=lobpcg", "pc_type=gamg", "tolerance=1e-9"}));
  const EigenResult r = distributed_eigs(fem, k, solver);
  REQUIRE(r.values.size() == k);
  CHECK((r.values - serial.values).cwiseAbs().maxCoeff() < 1e-6 * serial.values.maxCoeff());
}

// End to end on one machine: digitize sphere1, extract the surface, true normals,
// corrected FEM, the system the paper factorizes, CHOLMOD analyze / factorize / solve. For every
// stage: the time, the resident memory after it (and the peak during it), and the bytes of what it
// keeps, per surfel. Then the first-call cost of the FEM and interpolated assemblies: the first call,
// a second one (fresh output again) and a refill of the previous output (assemble_into), with the
// page faults of each (docs/scale.md "First call").
//
//   ./build/bench/bench_end_to_end [--h 0.002] [--system poisson|heat] [--ordering geometric|amd|metis]
//                                  [--no-solve] [--first-call-only]
//
// Not a Google Benchmark: each stage runs once, as the CLI runs it (`corrlap solve --shape sphere1
// --h H --bbox -1.5 1.5 --normals true --method fem --solver cholmod`).
#include <sys/resource.h>

#include <corrlap/backends/cholmod.hpp>
#include <corrlap/core/config.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/problems/problems.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "support.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {

long minor_faults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

// One line per stage: seconds, RSS after, peak during (since the last reset), bytes kept per surfel.
struct Table {
  double faces = 1.0;
  void header() const {
    std::printf("%-22s %9s %10s %10s %12s %12s\n", "stage", "seconds", "RSS MiB", "peak MiB", "kept B/surfel",
                "RSS B/surfel");
  }
  void row(const char* stage, double seconds, double kept_bytes, double rss = -1.0, double peak = -1.0) const {
    if (rss < 0.0) rss = bench::rss_mib();
    if (peak < 0.0) peak = bench::peak_rss_mib();
    std::printf("%-22s %9.3f %10.0f %10.0f %12.1f %12.1f\n", stage, seconds, rss, peak, kept_bytes / faces,
                rss * 1048576.0 / faces);
    std::fflush(stdout);
    bench::reset_peak_rss();
  }
};

// The first call of an assembly, a second one into fresh output, and a refill of the second's output.
void first_call_costs(const SurfelMesh& mesh, const NormalFields& normals, const char* method) {
  auto d = make_discretization(method);
  const Config params;
  long faults = minor_faults();
  Stopwatch watch;
  Operators first = d->assemble(mesh, normals, params);
  const double first_s = watch.elapsed();
  const long first_faults = minor_faults() - faults;
  first = Operators();  // freed: large blocks go back to the kernel, as between CLI runs
  faults = minor_faults();
  watch.restart();
  Operators second = d->assemble(mesh, normals, params);
  const double second_s = watch.elapsed();
  const long second_faults = minor_faults() - faults;
  faults = minor_faults();
  watch.restart();
  d->assemble_into(mesh, normals, params, second);
  const double into_s = watch.elapsed();
  const long into_faults = minor_faults() - faults;
  // What clearing fresh memory of the output's size costs on its own: touch a fresh buffer.
  const std::size_t bytes = std::size_t(bench::sparse_bytes(second.L) + bench::sparse_bytes(second.M));
  double touch_s = 0.0;
  if (bytes > 0) {
    volatile char* p = static_cast<char*>(std::malloc(bytes));
    watch.restart();
    for (std::size_t i = 0; i < bytes; i += 4096) p[i] = 1;
    touch_s = watch.elapsed();
    std::free(const_cast<char*>(p));
  }
  std::printf(
      "%-13s first %.3f s (%ld faults), again %.3f s (%ld faults), refill %.3f s (%ld faults); "
      "touching %.0f MiB of fresh memory alone %.3f s\n",
      method, first_s, first_faults, second_s, second_faults, into_s, into_faults, double(bytes) / 1048576.0, touch_s);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  double h = 0.002;
  std::string system = "poisson", ordering = "geometric";
  bool solve = true, first_call_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--h" && i + 1 < argc)
      h = std::stod(argv[++i]);
    else if (a == "--system" && i + 1 < argc)
      system = argv[++i];
    else if (a == "--ordering" && i + 1 < argc)
      ordering = argv[++i];
    else if (a == "--no-solve")
      solve = false;
    else if (a == "--first-call-only")
      first_call_only = true;
    else {
      std::fprintf(stderr,
                   "usage: %s [--h H] [--system poisson|heat] [--ordering NAME] [--no-solve] [--first-call-only]\n",
                   argv[0]);
      return 2;
    }
  }
  std::printf("sphere1, h = %g, box [-1.5, 1.5]^3, system %s, ordering %s\n", h, system.c_str(), ordering.c_str());
  bench::reset_peak_rss();
  Table table;
  const ImplicitShape shape = make_implicit_shape("sphere1");
  Stopwatch watch;
  VoxelGrid grid = digitize(shape, {.h = h, .min_aabb = -1.5, .max_aabb = 1.5});
  const double digitize_s = watch.elapsed();
  const double digitize_rss = bench::rss_mib(), digitize_peak = bench::peak_rss_mib();
  bench::reset_peak_rss();
  watch.restart();
  const SurfelMesh mesh = extract_surface(grid);
  const double extract_s = watch.elapsed();
  table.faces = double(mesh.num_faces());
  std::printf("%d surfels, %d vertices\n", mesh.num_faces(), mesh.num_vertices());
  table.header();
  table.row("digitize", digitize_s, double(grid.memory_bytes()), digitize_rss, digitize_peak);
  const double mesh_bytes =
      double(mesh.positions.size()) * 8 + double(mesh.faces.size()) * 4 + double(mesh.surfels.size()) * sizeof(Surfel);
  table.row("extract surface", extract_s, mesh_bytes);
  grid = VoxelGrid();  // true normals need the shape only
  table.row("drop the voxels", 0.0, 0.0);

  watch.restart();
  NormalFields normals;
  normals.face = true_face_normals(shape, mesh);
  table.row("true face normals", watch.elapsed(), double(normals.face.size()) * 8);

  if (first_call_only) {
    normals.vertex = vertex_normals_from_face_normals(normals.face, mesh.faces, mesh.num_vertices());
    first_call_costs(mesh, normals, "fem");
    first_call_costs(mesh, normals, "interpolated");
    return 0;
  }

  watch.restart();
  Operators ops = make_discretization("fem")->assemble(mesh, normals, Config());
  table.row("fem L, M", watch.elapsed(), bench::sparse_bytes(ops.L) + bench::sparse_bytes(ops.M));
  if (!solve) return 0;

  // The system: -L without vertex 0's row and column (docs/math.md §10.4), or M - dt L (§10.3).
  watch.restart();
  const Eigen::Index n = ops.L.rows();
  SpMat A;
  Eigen::MatrixX3d unknown_positions;
  if (system == "heat") {
    A = ops.M - 0.035 * h * ops.L;
    unknown_positions = mesh.positions;
  } else {
    A = pinned_system(ops.L, 0);  // what solve_neumann_poisson factorizes
    unknown_positions = mesh.positions.bottomRows(n - 1);
  }
  A.makeCompressed();
  Eigen::VectorXd b = A * Eigen::VectorXd::Ones(A.rows());
  table.row("system matrix", watch.elapsed(), bench::sparse_bytes(A));

  CholmodSolver solver;
  solver.configure(Config::from_key_values({"ordering=" + ordering}));
  solver.set_positions(unknown_positions);
  watch.restart();
  solver.analyze(A);
  table.row("cholmod analyze", watch.elapsed(), 0.0);
  watch.restart();
  solver.factorize(A);
  const double factor_bytes = solver.info().factor_nonzeros * 8;
  table.row("cholmod factorize", watch.elapsed(), factor_bytes);
  watch.restart();
  const Eigen::VectorXd x = solver.solve(b);
  table.row("cholmod solve", watch.elapsed(), double(x.size()) * 8);
  std::printf("ordering %s, factor %.3g entries, %.3g flops; |x - 1|_inf = %.2e\n", solver.info().ordering.c_str(),
              solver.info().factor_nonzeros, solver.info().factor_flops, (x.array() - 1.0).abs().maxCoeff());
  return 0;
}

#include "study.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/backends/iterative.hpp>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/stopwatch.hpp>
#include <corrlap/discretizations/assembly/quad_pattern.hpp>
#include <corrlap/discretizations/heat_kernel.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/problems/problems.hpp>
#include <corrlap/problems/test_functions.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <corrlap/surface/mesh_voxelization.hpp>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <sstream>

#include "cotan_reference.hpp"
#include "detail/repeats.hpp"

namespace corrlap {

StudyKind parse_study_kind(const std::string& name) {
  if (name == "forward") return StudyKind::Forward;
  if (name == "backward") return StudyKind::Backward;
  if (name == "eigen") return StudyKind::Eigen;
  if (name == "cotan") return StudyKind::Cotan;
  throw InputError("unknown study '" + name + "': expected forward, backward, eigen or cotan");
}

const char* to_string(StudyKind kind) {
  switch (kind) {
    case StudyKind::Forward:
      return "forward";
    case StudyKind::Backward:
      return "backward";
    case StudyKind::Eigen:
      return "eigen";
    case StudyKind::Cotan:
      return "cotan";
  }
  return "?";
}

double StudyOptions::forward_diffusion() const { return naive ? 0.0 : diffusion.value_or(kDefaultStudyDiffusion); }

void StudyOptions::validate() const {
  const std::string study = std::string("study ") + to_string(kind);
  if (methods.empty()) throw InputError("study: no method given", "methods");
  detail::refuse_repeats(methods, "method", "methods", study);
  const std::vector<std::string> known = discretization_registry().names();
  for (const std::string& m : methods)
    if (std::find(known.begin(), known.end(), m) == known.end()) (void)make_discretization(m);  // lists the names
  for (const std::string& kv : method_params) {
    const std::string key = kv.substr(0, kv.find('='));
    bool known_key = false;
    for (const std::string& m : methods) known_key = known_key || make_discretization(m)->parameters().find(key);
    if (kv.find('=') == std::string::npos || !known_key)
      throw InputError("study: method parameter '" + kv + "': no method of the study has the key '" + key + "'");
  }
  if (kind == StudyKind::Cotan) {
    if (mesh_file.empty()) throw InputError("study cotan: no mesh given", "mesh_file");
    if (resolutions.empty())
      throw InputError("study cotan: the list of resolutions is empty (e.g. 128,256)", "resolutions");
    for (int n : resolutions)
      if (n < 4 || n > 4096)
        throw InputError("study cotan: resolution " + std::to_string(n) + " must be in [4, 4096] voxels",
                         "resolutions");
    detail::refuse_repeats(resolutions, "resolution", "resolutions", study);
    if (shape != StudyOptions{}.shape)
      throw InputError("study cotan: the surface is the mesh (mesh_file), not an implicit shape: shape '" + shape +
                           "' does not apply",
                       "shape");
    if (refine_vertices < 0 || refine_vertices > 100000000)
      throw InputError("study cotan: refine_vertices must be in [0, 1e8]", "refine_vertices");
    if (reference_values != "interpolated" && reference_values != "at-foot")
      throw InputError("study cotan: reference values '" + reference_values + "': expected interpolated or at-foot",
                       "reference_values");
    if (reference_laplacian != "plain" && reference_laplacian != "diffused")
      throw InputError("study cotan: reference Laplacian '" + reference_laplacian + "': expected plain or diffused",
                       "reference_laplacian");
    (void)study_normal_source(*this);
  } else {
    if (h.empty()) throw InputError("study: the list of grid steps h is empty", "h");
    for (double step : h)
      if (!(step > 0.0) || !std::isfinite(step)) {
        std::ostringstream os;
        os << "study: grid step h = " << step << " must be positive and finite";
        throw InputError(os.str(), "h");
      }
    detail::refuse_repeats(h, "grid step h =", "h", study);
    // The reference values (the test functions' Laplacians, the eigenvalues l(l+1)) are those of
    // the unit sphere: any other shape would be compared against the wrong truth.
    if (make_implicit_shape(shape).sphere_radius() != 1.0)
      throw InputError(study + ": shape '" + shape +
                           "' has no reference solution: the exact values are those of the unit sphere; use sphere1 "
                           "(x^2+y^2+z^2-1), or the cotan study for a surface given as a mesh",
                       "shape");
    (void)study_normal_source(*this);
  }
  if (kind != StudyKind::Eigen) {
    if (functions.empty()) throw InputError("study: no test function given (functions: x2, expx, p6)", "functions");
    for (const std::string& f : functions) (void)test_function(f);  // InputError listing the names
    detail::refuse_repeats(functions, "test function", "functions", study);
  }
  if (centers < 1 || centers > 10000) throw InputError("study: centers must be in [1, 10000]", "centers");
  if (kind == StudyKind::Forward || kind == StudyKind::Cotan) {
    if (naive && diffusion)
      throw InputError(study +
                           ": naive and diffusion exclude each other: naive is dt = 0, diffusion sets dt = "
                           "diffusion * h; give one of them",
                       "naive");
    if (diffusion && !(*diffusion > 0.0 && std::isfinite(*diffusion)))
      throw InputError(study + ": diffusion must be positive and finite (naive gives dt = 0)", "diffusion");
  } else if (naive || diffusion) {
    throw InputError(study + ": " + (naive ? "naive" : "diffusion") +
                         " belongs to the forward and cotan studies (the evaluation X = (M - dt L)^-1 L f)",
                     naive ? "naive" : "diffusion");
  }
  if (kind == StudyKind::Eigen && (k < 1 || k > 1000))
    throw InputError("study: k (the number of eigenvalues) must be in [1, 1000]", "k");
  if (linear_solver != "auto") (void)make_linear_solver(linear_solver);  // InputError listing the backends
  if (!(min_aabb < max_aabb) || !std::isfinite(min_aabb) || !std::isfinite(max_aabb))
    throw InputError("study: the box needs finite MIN < MAX", "bbox");
  if (offset < 0) throw InputError("study: offset must be >= 0", "offset");
  if (!(ii_k > 0) || !std::isfinite(ii_k) || !std::isfinite(ii_alpha))
    throw InputError("study: II radius parameters must be positive and finite");
}

NormalSource study_normal_source(const StudyOptions& o) {
  std::optional<NormalSource> source;
  if (o.normals == "mesh") {
    source = NormalSource::Given;  // the reference mesh's normals, handed to resolve_normals
  } else {
    try {
      source = parse_normal_source(o.normals);
    } catch (const InputError&) {
    }
  }
  if (o.kind == StudyKind::Cotan) {
    if (source != NormalSource::Given && source != NormalSource::II)
      throw InputError("study cotan: normals '" + o.normals + "': expected mesh (the reference's) or ii", "normals");
  } else if (source != NormalSource::True && source != NormalSource::II && source != NormalSource::Exact) {
    throw InputError("study: normals '" + o.normals + "': expected true, ii or exact" +
                         (o.normals == "mesh" ? " (mesh normals belong to the cotan study)" : ""),
                     "normals");
  }
  return *source;
}

StudySurface study_surface(const StudyOptions& o, double h, const Eigen::Vector3d& c) {
  ImplicitShapeInput input;
  input.shape = o.shape;
  input.center = c;
  input.digitization.h = h;
  input.digitization.min_aabb = o.min_aabb;
  input.digitization.max_aabb = o.max_aabb;
  input.digitization.offset = o.offset;
  StudySurface s;
  s.surface = load_surface(input);
  NormalRequest request;
  request.source = study_normal_source(o);
  request.ii = IIParams{.k = o.ii_k, .alpha = o.ii_alpha};
  s.normals = resolve_normals(s.surface, NormalKind::Vertex, request, "study");
  return s;
}

std::vector<double> parse_grid_steps(const std::string& text) {
  const auto fail = [&](const std::string& why) -> std::vector<double> {
    throw InputError("grid steps '" + text + "': " + why + " (expected a list 0.1,0.05 or A:B:N)");
  };
  const auto number = [&](const std::string& s) {
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size()) fail("'" + s + "' is not a number");
    if (!(v > 0.0) || !std::isfinite(v)) fail("h = " + s + " must be positive and finite");
    return v;
  };
  std::vector<double> out;
  if (text.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::stringstream ss(text);
    for (std::string p; std::getline(ss, p, ':');) parts.push_back(p);
    if (parts.size() != 3) return fail("a range needs three fields A:B:N");
    const double a = number(parts[0]), b = number(parts[1]);
    char* end = nullptr;
    const long n = std::strtol(parts[2].c_str(), &end, 10);
    if (parts[2].empty() || end != parts[2].c_str() + parts[2].size() || n < 1 || n > 1000)
      return fail("N = '" + parts[2] + "' must be an integer in [1, 1000]");
    if (n == 1) return {a};
    for (long i = 0; i < n; ++i) {
      // Rounded to 12 significant digits, so that 0.1:0.0125:4 gives 0.05 and 0.025 exactly as
      // typed (not 0.05000000000000001), the same values a list would give.
      const double step = std::exp(std::log(a) + (std::log(b) - std::log(a)) * double(i) / double(n - 1));
      char text_step[32];
      std::snprintf(text_step, sizeof text_step, "%.12g", step);
      out.push_back(std::strtod(text_step, nullptr));
    }
    return out;
  }
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(number(item));
  if (out.empty()) return fail("the list is empty");
  return out;
}

Eigen::Vector3d study_center_offset(unsigned long long seed, int index, int count) {
  if (count <= 1) return Eigen::Vector3d::Zero();
  // splitmix64: a fixed, documented generator (std::uniform_real_distribution differs between
  // standard libraries), so that a seed gives the same centres everywhere.
  std::uint64_t state = seed * 0x9E3779B97F4A7C15ull + std::uint64_t(index) * 0xD1B54A32D192ED03ull;
  const auto next = [&state] {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  Eigen::Vector3d o;
  for (int a = 0; a < 3; ++a) o[a] = double(next() >> 11) * 0x1.0p-53 - 0.5;
  return o;
}

namespace {

// The method parameters that this method accepts: a key=value list shared by all methods (e.g.
// orientation=warn) applies to the methods that know the key.
Config params_for(const Discretization& d, const std::vector<std::string>& key_values) {
  std::vector<std::string> mine;
  for (const std::string& kv : key_values) {
    const std::string key = kv.substr(0, kv.find('='));
    if (d.parameters().find(key)) mine.push_back(kv);
  }
  return Config::from_key_values(mine);
}

// The surface of one (h, centre): shared by every method, with the reference values of the test
// functions where the operators live (vertices, or surfel centres for the heat kernel, §6).
struct SharedSurface {
  SurfelMesh mesh;
  NormalFields normals;  // face and vertex
  std::optional<QuadPattern> pattern;
  Eigen::MatrixX3d face_centres;
  Eigen::MatrixXd vertex_f, vertex_laplacian, face_f, face_laplacian;  // #points x #functions
};

// docs/math.md §10.1: the functions at the radial projections onto the unit sphere of centre c.
void sample_sphere(const std::vector<const TestFunction*>& functions, const Eigen::MatrixX3d& points,
                   const Eigen::Vector3d& c, Eigen::MatrixXd& f, Eigen::MatrixXd& laplacian) {
  f.resize(points.rows(), Eigen::Index(functions.size()));
  laplacian.resizeLike(f);
  for (std::size_t j = 0; j < functions.size(); ++j) {
    const TestFunctionSamples samples = sample_on_unit_sphere(*functions[j], points, c);
    f.col(Eigen::Index(j)) = samples.f;
    laplacian.col(Eigen::Index(j)) = samples.laplacian;
  }
}

SharedSurface build_surface(const StudyOptions& o, double h, const Eigen::Vector3d& c,
                            const std::vector<const TestFunction*>& functions) {
  SharedSurface s;
  StudySurface base = study_surface(o, h, c);
  s.mesh = std::move(base.surface.mesh);
  s.normals = std::move(base.normals);
  s.pattern = QuadPattern::build(s.mesh);
  s.face_centres = s.mesh.face_centroids();
  if (o.kind != StudyKind::Eigen) {
    sample_sphere(functions, s.mesh.positions, c, s.vertex_f, s.vertex_laplacian);
    sample_sphere(functions, s.face_centres, c, s.face_f, s.face_laplacian);
  }
  return s;
}

// docs/math.md §10.6: the reference mesh translated by c, digitized at step h; values (and, for
// normals "mesh", the normals) projected from the reference onto the vertices and surfel centres.
SharedSurface build_mesh_surface(const StudyOptions& o, double h, const Eigen::Vector3d& c,
                                 const CotanReference& reference) {
  SharedSurface s;
  PolygonMesh moved;
  moved.positions = reference.positions.rowwise() + c.transpose();
  moved.faces.reserve(std::size_t(reference.triangles.rows()), 3 * std::size_t(reference.triangles.rows()));
  for (Eigen::Index t = 0; t < reference.triangles.rows(); ++t)
    moved.faces.push_back({reference.triangles(t, 0), reference.triangles(t, 1), reference.triangles(t, 2)});
  MeshVoxelizationParams p;
  p.h = h;
  const VoxelGrid grid = voxelize_mesh(moved, p);
  s.mesh = extract_surface(grid);
  s.face_centres = s.mesh.face_centroids();
  const ReferenceValues values =
      o.reference_values == "at-foot" ? ReferenceValues::AtFoot : ReferenceValues::Interpolated;
  const double dt = o.reference_laplacian == "diffused" ? o.forward_diffusion() * h : 0.0;
  const Eigen::MatrixXd truth = diffused_reference_laplacian(reference, dt);
  ReferenceSamples at_vertices = sample_reference(reference, truth, s.mesh.positions, c, values);
  ReferenceSamples at_faces = sample_reference(reference, truth, s.face_centres, c, values);
  // "mesh": the reference's normals as given normals; "ii": estimated from the voxels.
  NormalRequest request;
  request.source = study_normal_source(o);
  if (request.source == NormalSource::Given) {
    request.vertex_normals = std::move(at_vertices.normals);
    request.face_normals = std::move(at_faces.normals);
  }
  request.ii = IIParams{.k = o.ii_k, .alpha = o.ii_alpha};
  s.normals = resolve_normals(s.mesh, NormalKind::Vertex, request, nullptr, &grid, "study");
  s.pattern = QuadPattern::build(s.mesh);
  s.vertex_f = std::move(at_vertices.f);
  s.vertex_laplacian = std::move(at_vertices.laplacian);
  s.face_f = std::move(at_faces.f);
  s.face_laplacian = std::move(at_faces.laplacian);
  return s;
}

// The backend for one method's systems. "auto": CHOLMOD, except for operators with many nonzeros per
// row: the heat kernel couples every surfel within K sqrt(2t) (~2000 per row at h = 0.0125, §6), and
// the Cholesky factor of such a matrix fills in far beyond it, while Jacobi CG needs a few products.
// And except for the forward systems A = M - dt L (docs/math.md §10.3): dt = 0.035 h keeps them close
// to the mass matrix, kappa(A) ~ kappa(M) (1 + dt lambda_max(M^-1 L)) = O(1/h) with lambda_max ~ 1/h^2,
// so Jacobi CG converges in a few dozen cheap products where CHOLMOD factorizes (bench/RESULTS.md,
// "corrlap study").
std::string solver_for(const std::string& choice, const Eigen::SparseMatrix<double>& L, StudyKind kind) {
  if (choice != "auto") return choice;
  if (kind == StudyKind::Forward || kind == StudyKind::Cotan) return "cg";
  return L.nonZeros() > 64 * L.rows() ? "cg" : "cholmod";
}

// Overwrites L with M - dt L (compressed). In L's own storage when M is diagonal and L stores its
// whole diagonal (lumped masses, the heat kernel): the heat kernel's L is the largest matrix of a
// study (~2000 entries per row), and a copy of it was the memory peak of a forward unit. (Eigen
// 3.4's SparseMatrix has no move constructor: by-value passing or returning would copy.)
void make_forward_system(Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M, double dt) {
  bool diagonal_mass = true;
  for (Eigen::Index j = 0; j < M.outerSize() && diagonal_mass; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(M, j); it; ++it) diagonal_mass = diagonal_mass && it.row() == j;
  L.makeCompressed();
  std::vector<double*> diagonal(std::size_t(L.rows()), nullptr);
  for (Eigen::Index j = 0; j < L.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, j); it; ++it)
      if (it.row() == j) diagonal[std::size_t(j)] = &it.valueRef();
  const bool in_place = diagonal_mass && std::find(diagonal.begin(), diagonal.end(), nullptr) == diagonal.end();
  if (dt == 0.0 || !in_place) {  // the naive evaluation (A = M), or a general pair
    Eigen::SparseMatrix<double> A = dt == 0.0 ? M : Eigen::SparseMatrix<double>(M - dt * L);
    A.makeCompressed();
    L.swap(A);
    return;
  }
  for (Eigen::Index k = 0; k < L.nonZeros(); ++k) L.valuePtr()[k] *= -dt;
  for (Eigen::Index j = 0; j < M.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(M, j); it; ++it) *diagonal[std::size_t(j)] += it.value();
}

// Forward evaluation (docs/math.md §10.3) X = (M - dt L)^{-1} L F with the heat kernel in compact
// lattice form (heat_kernel_lattice.hpp) and the Jacobi CG of the "cg" backend: what the "auto"
// solver does with the assembled matrix (solver_for), at half the memory traffic per product and
// without assembling values. nullopt when the lattice form does not apply to the parameters.
// `storage`: the previous unit's kernel, whose memory this one reuses; it then holds this one's.
std::optional<Eigen::MatrixXd> heat_kernel_forward(const SharedSurface& s, const Config& params,
                                                   const Eigen::MatrixXd& F, double dt, Eigen::VectorXd& mass,
                                                   std::optional<LatticeHeatKernel>& storage) {
  std::optional<LatticeHeatKernelPair> pair =
      assemble_heat_kernel_lattice(s.mesh, s.normals, params, storage ? &*storage : nullptr);
  if (!pair) return std::nullopt;
  struct KeepStorage {  // on every exit, errors included
    std::optional<LatticeHeatKernelPair>& pair;
    std::optional<LatticeHeatKernel>& storage;
    ~KeepStorage() {
      storage.reset();
      storage.emplace(std::move(pair->L));
    }
  } keep{pair, storage};
  if (!pair->contract_risk.empty())
    throw NumericalError("the operators may break their contract: " + pair->contract_risk);
  const LatticeHeatKernel& L = pair->L;
  mass = pair->mass;
  Eigen::MatrixXd LFt;
  L.multiply_transposed(F.transpose(), LFt);
  if (dt == 0.0) return Eigen::MatrixXd(mass.cwiseInverse().asDiagonal() * LFt.transpose());  // naive: A = M
  SymmetricOperator A;                                                                        // A = M - dt L
  A.rows = L.rows();
  A.diagonal = mass - dt * L.diagonal();
  A.multiply_transposed = [&](const Eigen::MatrixXd& Xt, Eigen::MatrixXd& Yt) {
    L.multiply_transposed(Xt, Yt);
    Yt = (Xt * mass.asDiagonal()) - dt * Yt;
  };
  return conjugate_gradient(A, LFt.transpose());
}

// "fem at h = 0.05, centre 3: <what>" for errors raised inside a unit.
[[noreturn]] void rethrow_in_unit(const std::exception& e, const std::string& method, double h, int center) {
  std::ostringstream os;
  os << "study: " << method << " at h = " << h << ", centre " << center << ": " << e.what();
  if (dynamic_cast<const InputError*>(&e)) throw InputError(os.str());
  throw NumericalError(os.str());
}

}  // namespace

void run_study(const StudyOptions& o, const StudyCallbacks& cb) {
  o.validate();
  // Cotan: the reference once per study; resolution N of a mesh whose longest side is 2 is h = 2 / N.
  std::vector<const TestFunction*> functions;
  for (const std::string& f : o.functions) functions.push_back(&test_function(f));
  std::optional<CotanReference> reference;
  std::vector<double> hs = o.h;
  if (o.kind == StudyKind::Cotan) {
    reference = make_cotan_reference(read_mesh(o.mesh_file), functions, o.refine_vertices);
    hs.clear();
    for (int n : o.resolutions) hs.push_back(2.0 / double(n));
  }
  std::sort(hs.begin(), hs.end(), std::greater<>());  // coarse first: early rows, early errors

  // Work of a unit ~ number of surfels ~ 1/h^2: the fraction of it done drives the ETA.
  double total_cost = 0;
  for (double h : hs) total_cost += double(o.centers) * double(o.methods.size()) / (h * h);
  StudyProgress progress;
  progress.total = int(hs.size()) * o.centers * int(o.methods.size());
  double cost_done = 0;
  const auto report = [&](double h, int center, const std::string& method) {
    ++progress.done;
    cost_done += 1.0 / (h * h);
    progress.h = h;
    progress.center = center;
    progress.method = method;
    progress.cost_fraction = cost_done / total_cost;
    if (cb.progress) cb.progress(progress);
  };

  std::optional<LatticeHeatKernel> heat_kernel_storage;  // reused from unit to unit (no fresh pages)
  for (double h : hs)
    for (int center = 0; center < o.centers; ++center) {
      std::vector<std::string> to_compute;
      for (const std::string& m : o.methods)
        if (cb.already_done && cb.already_done(h, center, m))
          report(h, center, m);
        else
          to_compute.push_back(m);
      if (to_compute.empty()) continue;
      const Eigen::Vector3d c = h * study_center_offset(o.seed, center, o.centers);
      const SharedSurface s = reference ? build_mesh_surface(o, h, c, *reference) : build_surface(o, h, c, functions);
      for (const std::string& method : to_compute) {
        const Stopwatch watch;
        // One row per function of a forward or backward unit.
        const auto emit_rows = [&](const std::vector<ErrorNorms>& errors, double t) {
          std::vector<StudyRow> rows;
          for (std::size_t j = 0; j < functions.size(); ++j) {
            StudyRow row;
            row.study = to_string(o.kind);
            row.method = method;
            row.normals = o.normals;
            row.function = functions[j]->name;
            row.h = h;
            row.center = center;
            row.c = c;
            row.vertices = s.mesh.num_vertices();
            row.faces = s.mesh.num_faces();
            row.error_linf = errors[j].linf;
            row.error_l2 = errors[j].l2;
            row.time_s = t;
            if (!std::isfinite(row.error_linf) || !std::isfinite(row.error_l2))
              throw NumericalError("the error of " + row.function + " is not finite");
            rows.push_back(row);
          }
          if (cb.rows) cb.rows(rows);
        };
        try {
          const auto d = make_discretization(method);
          const Config params = params_for(*d, o.method_params);
          if ((o.kind == StudyKind::Forward || o.kind == StudyKind::Cotan) && method == "heat-kernel" &&
              (o.linear_solver == "auto" || o.linear_solver == "cg")) {
            Eigen::VectorXd mass;
            const std::optional<Eigen::MatrixXd> X =
                heat_kernel_forward(s, params, s.face_f, o.forward_diffusion() * h, mass, heat_kernel_storage);
            if (X) {
              Eigen::SparseMatrix<double> M(mass.size(), mass.size());
              M.setIdentity();
              M.diagonal() = mass;
              std::vector<ErrorNorms> errors(functions.size());
              for (std::size_t j = 0; j < functions.size(); ++j)
                errors[j] = error_norms(M, X->col(Eigen::Index(j)) - s.face_laplacian.col(Eigen::Index(j)));
              emit_rows(errors, watch.elapsed());
              report(h, center, method);
              continue;
            }
          }
          Operators ops = d->assemble(s.mesh, s.normals, params, *s.pattern);
          if (!ops.contract_risk.empty())
            throw NumericalError("the operators may break their contract: " + ops.contract_risk);
          // Values live where the operator does: vertices, or surfel centres (heat kernel, §6).
          const bool on_faces = ops.domain == Operators::Domain::Faces;
          if (o.kind == StudyKind::Eigen) {
            Config config;
            config.set("solver", solver_for(o.linear_solver, ops.L, o.kind));
            const EigenResult r = make_eigen_solver(kDefaultEigenSolver, config)->solve(ops.L, ops.M, o.k);
            const double t = watch.elapsed();
            std::vector<EigenRow> rows;
            for (Eigen::Index i = 0; i < r.values.size(); ++i) {
              EigenRow row;
              row.method = method;
              row.normals = o.normals;
              row.h = h;
              row.center = center;
              row.index = int(i);
              const double l = std::floor(std::sqrt(double(i)));  // index i is in the multiplet l
              row.exact = l * (l + 1.0);
              row.computed = r.values[i];
              row.relative_error =
                  i == 0 ? std::numeric_limits<double>::quiet_NaN() : (row.computed - row.exact) / row.exact;
              row.time_s = t;
              rows.push_back(row);
            }
            if (cb.eigen_rows) cb.eigen_rows(rows);
          } else {
            // Every function at once: one factorization per method and unit.
            const Eigen::MatrixXd& F = on_faces ? s.face_f : s.vertex_f;
            const Eigen::MatrixXd& Lap = on_faces ? s.face_laplacian : s.vertex_laplacian;
            auto solver = make_linear_solver(solver_for(o.linear_solver, ops.L, o.kind));
            // The unknowns' positions order the factorization (LinearSolver::set_positions).
            const Eigen::MatrixX3d unknown_positions = on_faces ? s.mesh.face_centroids() : s.mesh.positions;
            std::vector<ErrorNorms> errors(functions.size());
            if (o.kind == StudyKind::Backward) {
              // docs/math.md §10.4: L g = M b_c, vertex 0 pinned to f(q_0), errors with means removed.
              const Eigen::MatrixXd G = solve_neumann_poisson_columns(ops.L, ops.M, Lap, *solver, F.row(0).transpose(),
                                                                      0, &unknown_positions);
              for (std::size_t j = 0; j < functions.size(); ++j)
                errors[j] = poisson_errors(ops.M, G.col(Eigen::Index(j)), F.col(Eigen::Index(j)));
            } else {
              // docs/math.md §10.3: X = (M - dt L)^{-1} L f, dt = diffusion * h (0: naive).
              const double dt = o.forward_diffusion() * h;
              const Eigen::MatrixXd LF = ops.L * F;
              make_forward_system(ops.L, ops.M, dt);  // ops.L is now A = M - dt L
              solver->set_positions(unknown_positions);
              solver->compute(std::move(ops.L));  // cg keeps A instead of a copy
              const Eigen::MatrixXd X = solver->solve(LF);
              for (std::size_t j = 0; j < functions.size(); ++j)
                errors[j] = error_norms(ops.M, X.col(Eigen::Index(j)) - Lap.col(Eigen::Index(j)));
            }
            emit_rows(errors, watch.elapsed());
          }
        } catch (const Error& e) {
          rethrow_in_unit(e, method, h, center);
        }
        report(h, center, method);
      }
    }
}

}  // namespace corrlap

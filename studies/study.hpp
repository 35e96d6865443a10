#pragma once
// The evaluation studies of the paper (§3) as a library: forward, backward (Poisson) and eigenvalue
// errors of any set of discretizations over a list of grid steps and random centres, and the
// forward comparison against the cotan Laplacian of a refined triangle mesh (§3.4)
// (docs/math.md §10; docs/studies.md). One study = options -> rows; the tables (summary, orders)
// are computed from the rows (study_tables.hpp), and the CLI (`corrlap study`) writes them as CSV.
#include <Eigen/Core>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/normal_estimation.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace corrlap {

/// Cotan: the forward protocol on a digitized triangle mesh, against the cotan Laplacian of the
/// refined mesh mapped to the digital surface (paper §3.4, docs/math.md §10.6, cotan_reference.hpp).
enum class StudyKind { Forward, Backward, Eigen, Cotan };
/// "forward" | "backward" | "eigen" | "cotan"; InputError listing the names otherwise.
StudyKind parse_study_kind(const std::string& name);
const char* to_string(StudyKind kind);

struct StudyOptions {
  StudyKind kind = StudyKind::Backward;
  std::vector<std::string> methods = {"fem"};   ///< registry names
  std::vector<double> h = {0.1, 0.05};          ///< grid steps (any order); cotan: 2 / resolutions
  std::vector<std::string> functions = {"x2"};  ///< docs/math.md §10.2 names (forward, backward)
  /// A normal source of the library's vocabulary (study_normal_source): "true", "ii" (docs/math.md
  /// §1.5, §7) or "exact" (the shape's normal at each vertex); cotan: "mesh" (the reference's
  /// normals, projected and interpolated, at vertices and surfel centres: given normals) or "ii"
  std::string normals = "true";
  double ii_k = 3.0, ii_alpha = 1.0 / 3.0;  ///< II radius k h^alpha (the paper's 1/3)
  int centers = 1;                          ///< N: centre 0 when 1, else uniform draws (§10.1)
  unsigned long long seed = 1;              ///< of the centre draws
  /// Implicit shape: the unit sphere (sphere1, or its polynomial), the only shape whose exact
  /// Laplacians and eigenvalues the studies know; the cotan study's surface is its mesh instead
  std::string shape = "sphere1";
  double min_aabb = -2.0, max_aabb = 2.0;  ///< docs/math.md §10.1 box
  int offset = 5;                          ///< extra voxels around the box
  /// Forward and cotan: dt = diffusion * h (§10.3); unset: kDefaultStudyDiffusion
  std::optional<double> diffusion;
  /// Forward and cotan: dt = 0 (X = M^-1 L f), the paper's naive evaluation. It is diffusion 0 by
  /// another name, so giving both is refused rather than letting one win.
  bool naive = false;
  int k = 49;  ///< eigen: number of eigenvalues
  /// Backend of the linear solves: a registered name, or "auto" (CHOLMOD; Jacobi CG for operators
  /// with more than 64 nonzeros per row, i.e. the heat kernel)
  std::string linear_solver = "auto";
  std::vector<std::string> method_params;  ///< key=value for every method (unknown keys skipped per method)
  // Cotan study (paper §3.4): the mesh scaled so that its longest side spans 2, hence h = 2 / N.
  std::string mesh_file;                           ///< triangle or polygon mesh (OBJ, PLY, OFF)
  std::vector<int> resolutions = {128, 256, 512};  ///< N: voxels along the longest side
  long long refine_vertices = 100000;              ///< Loop-subdivide the mesh up to this many vertices
  std::string reference_values = "interpolated";   ///< "interpolated" (the paper) | "at-foot" (cotan_reference.hpp)
  /// "plain": the truth is the cotan Laplacian M^-1 L f (paper §3.4); "diffused": the cotan forward
  /// evaluation (M - dt L)^-1 L f with the study's dt, so that both sides carry the same smoothing.
  std::string reference_laplacian = "plain";

  /// InputError naming the first invalid option (unknown method or function, h <= 0, empty lists,
  /// a value given twice, a shape without a reference, an option of another kind of study...).
  void validate() const;
  /// dt / h of the forward systems: 0 when naive, else diffusion or its default.
  double forward_diffusion() const;
};

/// dt = 0.035 h: the diffusion of the paper's forward evaluation (docs/math.md §10.3).
inline constexpr double kDefaultStudyDiffusion = 0.035;

/// The study's normals in the library's vocabulary (parse_normal_source): "true", "ii", "exact" for
/// the forward, backward and eigen studies; for the cotan study "mesh", its name for the given
/// normals of the reference mesh (NormalSource::Given), or "ii". InputError naming the valid ones.
NormalSource study_normal_source(const StudyOptions& options);

/// The surface and normals of one (h, centre) of a forward, backward or eigen study: the shape
/// centred at `center`, digitized in the study's box at step h (load_surface), its face and vertex
/// normals from resolve_normals with the study's source and II parameters. What run_study uses.
struct StudySurface {
  LoadedSurface surface;
  NormalFields normals;
};
StudySurface study_surface(const StudyOptions& options, double h, const Eigen::Vector3d& center);

/// Grid steps from "0.1,0.05,0.025" (a comma list) or "A:B:N" (N steps from A to B, equally spaced
/// in log h, both ends included). InputError naming the text for anything else, h <= 0 or N < 1.
std::vector<double> parse_grid_steps(const std::string& text);

/// The centre offset of centre `index` (of `count`), in units of h: 0 when count == 1, else uniform
/// in [-1/2, 1/2]^3 from the seed (the same offsets at every h; splitmix64, platform-independent).
Eigen::Vector3d study_center_offset(unsigned long long seed, int index, int count);

/// One result of a forward or backward study: a (method, function, h, centre).
struct StudyRow {
  std::string study, method, normals, function;
  double h = 0;
  int center = 0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  long long vertices = 0, faces = 0;
  double error_linf = 0, error_l2 = 0;
  double time_s = 0;  ///< assembly + solve of this method (shared work excluded)
};

/// One eigenvalue of an eigen study: -lambda_index against l(l+1) of the unit sphere.
struct EigenRow {
  std::string method, normals;
  double h = 0;
  int center = 0;
  int index = 0;
  double exact = 0, computed = 0;
  /// (computed - exact) / exact; NaN (an empty field) for index 0, whose exact value is 0: there
  /// `computed` is the absolute error itself
  double relative_error = 0;
  double time_s = 0;
};

/// Where the work stands: called after every (h, centre, method) unit with the counts, the
/// current unit's labels and the fraction of the estimated total cost done (work ~ 1/h^2).
struct StudyProgress {
  int done = 0, total = 0;
  double h = 0;
  int center = 0;
  std::string method;
  double cost_fraction = 0;
};

struct StudyCallbacks {
  /// Units (h, centre, method) already in a resumed results file: skipped when it returns true.
  std::function<bool(double h, int center, const std::string& method)> already_done;
  std::function<void(const std::vector<StudyRow>&)> rows;        ///< after each unit (forward, backward)
  std::function<void(const std::vector<EigenRow>&)> eigen_rows;  ///< after each unit (eigen)
  std::function<void(const StudyProgress&)> progress;
};

/// Runs the study. Work shared by the methods is done once per (h, centre): digitization, surface,
/// normals, reference values and the quad assembly pattern (cotan: the refined reference mesh and its
/// Laplacians once per study). Methods run one after the other (each uses every core),
/// so memory holds one operator set at a time. Throws InputError for bad options, the solver's
/// errors for failures (naming the method, h and centre).
void run_study(const StudyOptions& options, const StudyCallbacks& callbacks);

}  // namespace corrlap

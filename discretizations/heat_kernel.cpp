#include "heat_kernel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/discretizations/assembly/detail/storage.hpp>
#include <corrlap/discretizations/detail/heat_kernel_inputs.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>
#include <new>
#include <numbers>
#include <sstream>
#include <vector>

namespace corrlap {

double heat_kernel_time(double h, double k, double alpha) { return k * std::pow(h, alpha); }

namespace {

// Uniform grid of cell size R over the points: cells sorted by key, each cell's points in
// ascending index order (so candidate runs come out sorted).
class CellGrid {
 public:
  CellGrid(const Eigen::MatrixX3d& x, double R) : x_(x), R_(R) {
    const Eigen::Index n = x.rows();
    lower_ = x.colwise().minCoeff().transpose();
    const Eigen::Vector3d extent = x.colwise().maxCoeff().transpose() - lower_;
    for (int a = 0; a < 3; ++a)
      if (extent[a] / R > double(1 << 20))
        throw InputError("heat kernel: cut-off radius too small for the extent of the points");
    std::vector<std::pair<std::int64_t, int>> keyed(static_cast<std::size_t>(n));
    tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) { keyed[std::size_t(i)] = {key(cell_of(i)), int(i)}; });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    order_.resize(std::size_t(n));
    xyz_.resize(3 * std::size_t(n));
    for (std::size_t i = 0; i < keyed.size(); ++i) {
      order_[i] = keyed[i].second;
      for (int a = 0; a < 3; ++a) xyz_[3 * i + std::size_t(a)] = x(keyed[i].second, a);
      if (i == 0 || keyed[i].first != keyed[i - 1].first) {
        keys_.push_back(keyed[i].first);
        begin_.push_back(std::int64_t(i));
      }
    }
    begin_.push_back(std::int64_t(n));
  }

  Eigen::Vector3i cell_of(Eigen::Index i) const {
    Eigen::Vector3i c;
    for (int a = 0; a < 3; ++a) c[a] = int(std::floor((x_(i, a) - lower_[a]) / R_));
    return c;
  }
  static std::int64_t key(const Eigen::Vector3i& c) {
    return (std::int64_t(c[0] + 1) << 42) | (std::int64_t(c[1] + 1) << 21) | std::int64_t(c[2] + 1);
  }
  /// Range [first, last) of the cell in the cell-sorted order (empty if none).
  std::pair<std::int64_t, std::int64_t> cell(const Eigen::Vector3i& c) const {
    for (int a = 0; a < 3; ++a)
      if (c[a] < 0) return {0, 0};
    const std::int64_t k = key(c);
    auto it = std::lower_bound(keys_.begin(), keys_.end(), k);
    if (it == keys_.end() || *it != k) return {0, 0};
    const std::size_t id = std::size_t(it - keys_.begin());
    return {begin_[id], begin_[id + 1]};
  }
  /// Point index and coordinates (contiguous, so the candidate scan streams) of sorted entry e.
  int index(std::int64_t e) const { return order_[std::size_t(e)]; }
  const double* coords(std::int64_t e) const { return xyz_.data() + 3 * e; }

 private:
  const Eigen::MatrixX3d& x_;
  double R_;
  Eigen::Vector3d lower_;
  std::vector<std::int64_t> keys_, begin_;
  std::vector<int> order_;
  std::vector<double> xyz_;
};

struct Neighbour {
  int index;
  double d2;
  bool operator<(const Neighbour& o) const { return index < o.index; }
};

// Thread-local scratch: grows to the largest neighbourhood once, then is reused (no per-point
// allocation). n = number of valid entries in a.
struct Scratch {
  std::vector<Neighbour> a, b;
  std::size_t n = 0;
  std::vector<std::size_t> runs, runs2;
};

// Grid cells are R / kCellsPerRadius wide: the search covers (2 kCellsPerRadius + 1)^3 cells.
// Finer cells mean fewer candidates to reject (on a surface: (2.5R)^2 instead of (3R)^2 for 2).
constexpr int kCellsPerRadius = 2;

// Neighbours of point i (excluding i) strictly within distance R (R2 = R^2), in s.a[0, s.n);
// sorted by index when `sorted`.
void neighbours(const Eigen::MatrixX3d& x, const CellGrid& grid, Eigen::Index i, double R2, Scratch& s,
                bool sorted = true) {
  s.runs.clear();
  const Eigen::Vector3i c = grid.cell_of(i);
  const double xi = x(i, 0), yi = x(i, 1), zi = x(i, 2);
  std::pair<std::int64_t, std::int64_t>
      ranges[(2 * kCellsPerRadius + 1) * (2 * kCellsPerRadius + 1) * (2 * kCellsPerRadius + 1)];
  int nr = 0;
  std::size_t total = 0;
  for (int dx = -kCellsPerRadius; dx <= kCellsPerRadius; ++dx)
    for (int dy = -kCellsPerRadius; dy <= kCellsPerRadius; ++dy)
      for (int dz = -kCellsPerRadius; dz <= kCellsPerRadius; ++dz) {
        const auto r = grid.cell(c + Eigen::Vector3i(dx, dy, dz));
        if (r.first == r.second) continue;
        ranges[nr++] = r;
        total += std::size_t(r.second - r.first);
      }
  if (s.a.size() < total) s.a.resize(total);
  Neighbour* out = s.a.data();
  std::size_t n = 0;
  for (int k = 0; k < nr; ++k) {
    s.runs.push_back(n);
    for (std::int64_t e = ranges[k].first; e != ranges[k].second; ++e) {
      const double* y = grid.coords(e);
      const double ex = y[0] - xi, ey = y[1] - yi, ez = y[2] - zi;
      const double d2 = ex * ex + ey * ey + ez * ez;
      const int q = grid.index(e);
      out[n] = {q, d2};
      n += std::size_t((d2 < R2) & (q != i));  // branch-free: about half the candidates are rejected
    }
  }
  s.runs.push_back(n);
  s.n = n;
  if (!sorted) return;
  // Bottom-up merge of the sorted runs (one per cell): O(n log #cells), cheaper than a sort.
  if (s.b.size() < s.a.size()) s.b.resize(s.a.size());
  while (s.runs.size() > 2) {
    s.runs2.clear();
    std::size_t r = 0;
    for (; r + 2 < s.runs.size(); r += 2) {
      std::merge(s.a.begin() + std::ptrdiff_t(s.runs[r]), s.a.begin() + std::ptrdiff_t(s.runs[r + 1]),
                 s.a.begin() + std::ptrdiff_t(s.runs[r + 1]), s.a.begin() + std::ptrdiff_t(s.runs[r + 2]),
                 s.b.begin() + std::ptrdiff_t(s.runs[r]));
      s.runs2.push_back(s.runs[r]);
    }
    if (r + 1 < s.runs.size()) {  // odd run out: copy
      std::copy(s.a.begin() + std::ptrdiff_t(s.runs[r]), s.a.begin() + std::ptrdiff_t(s.runs[r + 1]),
                s.b.begin() + std::ptrdiff_t(s.runs[r]));
      s.runs2.push_back(s.runs[r]);
    }
    s.runs2.push_back(n);
    std::swap(s.a, s.b);
    std::swap(s.runs, s.runs2);
  }
}

// Entries of point i's neighbourhood s.a[0, s.n) that column i stores: all of them, or (Upper)
// only rows below i.
std::size_t stored_neighbours(const Scratch& s, Eigen::Index i, HeatKernelStorage storage) {
  if (storage == HeatKernelStorage::Full) return s.n;
  std::size_t k = 0;
  for (std::size_t e = 0; e < s.n; ++e) k += std::size_t(s.a[e].index < i);
  return k;
}

}  // namespace

std::int64_t heat_kernel_nonzeros(const Eigen::MatrixX3d& points, double t, double cutoff, HeatKernelStorage storage) {
  detail::check_heat_kernel_inputs(points, t, cutoff);
  const double R = cutoff * std::sqrt(2.0 * t);
  const CellGrid grid(points, R / kCellsPerRadius);
  tbb::enumerable_thread_specific<Scratch> scratch;
  std::vector<std::int64_t> count(std::size_t(points.rows()));
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, points.rows(), 256), [&](const auto& r) {
    Scratch& s = scratch.local();
    for (Eigen::Index i = r.begin(); i != r.end(); ++i) {
      neighbours(points, grid, i, R * R, s, false);
      count[std::size_t(i)] = std::int64_t(stored_neighbours(s, i, storage)) + 1;
    }
  });
  std::int64_t total = 0;
  for (auto c : count) total += c;
  return total;
}

Eigen::SparseMatrix<double> heat_kernel_matrix(const Eigen::MatrixX3d& points, const Eigen::VectorXd& mu, double t,
                                               double cutoff, HeatKernelForm form, HeatKernelStorage storage,
                                               const Eigen::MatrixX3d* tangent_normals) {
  detail::check_heat_kernel_inputs(points, t, cutoff);
  if (tangent_normals != nullptr) check_normals(*tangent_normals, points.rows(), "heat kernel: tangent normals");
  if (storage == HeatKernelStorage::Upper && form != HeatKernelForm::Symmetric)
    throw InputError("heat kernel: upper-triangle storage needs the symmetric form");
  const Eigen::Index n = points.rows();
  detail::check_heat_kernel_measures(mu, n);
  if (n > INT_MAX) throw InputError("heat kernel: too many points");
  const double R = cutoff * std::sqrt(2.0 * t);
  const double R2 = R * R, inv4t = 1.0 / (4.0 * t);
  const double c = 1.0 / (4.0 * std::numbers::pi * t * t);  // docs/math.md §6: 1 / (t (4 pi t)^{d/2}), d = 2
  const CellGrid grid(points, R / kCellsPerRadius);
  tbb::enumerable_thread_specific<Scratch> scratch;

  // Pass 1: column counts (neighbours + the diagonal).
  std::vector<std::int64_t> outer(std::size_t(n) + 1, 0);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 256), [&](const auto& r) {
    Scratch& s = scratch.local();
    for (Eigen::Index i = r.begin(); i != r.end(); ++i) {
      neighbours(points, grid, i, R2, s, false);
      outer[std::size_t(i) + 1] = std::int64_t(stored_neighbours(s, i, storage)) + 1;
    }
  });
  for (Eigen::Index i = 0; i < n; ++i) outer[std::size_t(i) + 1] += outer[std::size_t(i)];
  const std::int64_t nnz = outer[std::size_t(n)];
  if (nnz > std::int64_t(INT_MAX)) {
    std::ostringstream os;
    os << "heat kernel: " << nnz
       << " nonzeros exceed the 32-bit sparse index range; use a larger h or a smaller t/cutoff";
    throw NumericalError(os.str());
  }
  Eigen::SparseMatrix<double> A(n, n);
  try {
    // The arrays are first touched in pass 2; with 4 KiB pages their page faults are a large part
    // of the assembly (bench/RESULTS.md, "bench_heat_kernel", profile): storage on huge pages.
    detail::allocate_sparse_storage(A, Eigen::Index(nnz));
  } catch (const std::bad_alloc&) {
    std::ostringstream os;
    os << "heat kernel: " << nnz << " nonzeros (" << double(nnz) * 12.0 / 1e9 << " GB) do not fit in memory";
    throw NumericalError(os.str());
  }
  for (Eigen::Index i = 0; i <= n; ++i) A.outerIndexPtr()[i] = int(outer[std::size_t(i)]);
  int* inner = A.innerIndexPtr();
  double* values = A.valuePtr();

  // Pass 2: column j, written once. The neighbour relation is symmetric (bitwise-equal distances),
  // so column j's pattern is j's neighbourhood. Symmetric form: L[i][j] = c mu_i mu_j g(d),
  // L[j][j] = -mu_j sum_i c mu_i g. Pointwise form: A[i][j] = c mu_j g, and the diagonal is
  // minus the ROW sum of row j, -sum_i c mu_i g(d_ij): also computable from j's neighbourhood.
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 256), [&](const auto& r) {
    Scratch& s = scratch.local();
    for (Eigen::Index j = r.begin(); j != r.end(); ++j) {
      neighbours(points, grid, j, R2, s);
      std::int64_t out = outer[std::size_t(j)];
      std::int64_t diag_pos = -1;
      double row_sum = 0.0;  // sum_i c mu_i g(d_ij), in ascending i (deterministic)
      const double muj = mu[j];
      const bool upper = storage == HeatKernelStorage::Upper;
      for (std::size_t k = 0; k < s.n; ++k) {
        const Neighbour& nb = s.a[k];
        if (diag_pos < 0 && nb.index > j) diag_pos = out++;
        double d2 = nb.d2;
        if (tangent_normals != nullptr) {
          // Tangent-plane distance: drop the component of e along the mean normal. Symmetric in
          // (i, j) bit for bit (u_i + u_j commutes, e flips sign), so L stays symmetric.
          const Eigen::Vector3d e = points.row(nb.index) - points.row(j);
          const Eigen::Vector3d m = (tangent_normals->row(nb.index) + tangent_normals->row(j)).transpose();
          const double mm = m.squaredNorm();
          if (mm > 0.0) {
            const double en = e.dot(m);
            d2 = std::max(0.0, d2 - en * en / mm);
          }
        }
        const double g = c * std::exp(-d2 * inv4t);
        row_sum += mu[nb.index] * g;
        if (upper && nb.index > j) continue;  // the diagonal closes the column; keep summing
        inner[out] = nb.index;
        values[out] = form == HeatKernelForm::Symmetric ? mu[nb.index] * muj * g : muj * g;
        ++out;
      }
      if (diag_pos < 0) diag_pos = out++;
      inner[diag_pos] = int(j);
      values[diag_pos] = form == HeatKernelForm::Symmetric ? -muj * row_sum : -row_sum;
    }
  });
  return A;
}

namespace {

class HeatKernel final : public Discretization {
 public:
  std::string name() const override { return "heat-kernel"; }
  NormalKind required_normals() const override { return NormalKind::Face; }
  const ParameterList& parameters() const override {
    static const ParameterList list =
        ParameterList{
            Parameter::computed_real("t", "k h^alpha", "diffusion time; when absent, t = k h^alpha", "§6").above(0.0),
            Parameter::real("k", 0.1, "t = k h^alpha when t is absent", "§6").above(0.0),
            Parameter::real("alpha", 2.0 / 3.0, "t = k h^alpha when t is absent", "§6"),
            Parameter::real("cutoff", 3.0, "couple points closer than cutoff * sqrt(2t) (K)", "§6").above(0.0),
            Parameter::choice("distance", {"euclidean", "tangent"},
                              "euclidean | tangent: distances in the plane of the mean normal (corrlap extension; "
                              "removes the O(h^2/t) error of off-surface surfel centres; dual variant only)",
                              "§6"),
            Parameter::choice("variant", {"dual", "primal"},
                              "dual: surfel values (domain Faces) | primal: vertex values", "§6"),
            Parameter::choice("mass", {"measure", "identity"},
                              "measure: L = diag(mu) A symmetric, M = diag(mu) | identity: L = A pointwise, M = I",
                              "§6")}
            .append(normal_policy_parameters());
    return list;
  }

  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& params, const QuadPattern*,
                     Operators& out) const override {
    Setup s = setup(mesh, normals, params);
    // swap, not assign: Eigen 3.4's SparseMatrix has no move assignment, and a copy would double
    // the peak memory of the largest operator.
    Eigen::SparseMatrix<double> L = heat_kernel_matrix(
        s.points, s.mu, s.t, s.cutoff, s.symmetric ? HeatKernelForm::Symmetric : HeatKernelForm::Pointwise,
        HeatKernelStorage::Full, s.tangent ? &s.normals : nullptr);
    s.ops.L.swap(L);
    Eigen::SparseMatrix<double> D(s.mu.size(), s.mu.size());
    D.reserve(Eigen::VectorXi::Ones(s.mu.size()));
    for (Eigen::Index i = 0; i < s.mu.size(); ++i) D.insert(i, i) = s.symmetric ? s.mu[i] : 1.0;
    D.makeCompressed();
    s.ops.M.swap(D);
    move_operators(s.ops, out);
  }

  // Everything but the matrix: points, measures, t, cut-off and the Operators' other fields.
  struct Setup {
    Eigen::MatrixX3d points, normals;
    Eigen::VectorXd mu;
    double t = 0, cutoff = 0;
    bool symmetric = true, dual = true, tangent = false;
    Operators ops;
  };

  Setup setup(const SurfelMesh& mesh, const NormalFields& normals, const Config& config) const {
    const ParameterValues params = parameters().read(config, name());
    mesh.validate("heat-kernel");
    const std::string variant = params.choice("variant");
    const std::string mass = params.choice("mass");
    const double h = mesh.grid_step();
    double t = 0.0;
    if (const std::optional<double> given = params.optional_real("t")) {
      t = *given;
    } else {
      t = heat_kernel_time(h, params.real("k"), params.real("alpha"));
      if (!(t > 0) || !std::isfinite(t)) throw InputError("heat-kernel: k h^alpha must be positive", "k");
    }
    const double cutoff = params.real("cutoff");
    const std::string distance = params.choice("distance");
    if (distance == "tangent" && variant != "dual")
      throw InputError("heat-kernel: distance=tangent needs variant=dual (one normal per surfel)", "distance");

    Setup s;
    s.t = t;
    s.cutoff = cutoff;
    s.symmetric = mass == "measure";
    s.dual = variant == "dual";
    s.tangent = distance == "tangent";
    const PreparedNormals prepared = prepare_normals(mesh, normals, NormalKind::Face, params, name(), s.ops);
    const Eigen::MatrixX3d& u = prepared.matrix();
    const Eigen::MatrixX3d n = trivial_face_normals(mesh);
    const int F = mesh.num_faces();
    // docs/math.md §6: mu(s) = h^2 |u_s . n_s| (DGtal takes the absolute value); h^2 = |(x1-x0) x (x3-x0)|.
    Eigen::VectorXd mu(F);
    for (int f = 0; f < F; ++f) {
      const Eigen::Vector3d x0 = mesh.positions.row(mesh.faces(f, 0)), x1 = mesh.positions.row(mesh.faces(f, 1)),
                            x3 = mesh.positions.row(mesh.faces(f, 3));
      mu[f] = (x1 - x0).cross(x3 - x0).norm() * std::abs(u.row(f).dot(n.row(f)));
      if (!(mu[f] > 0)) {
        std::ostringstream os;
        os << "heat-kernel: face " << f << " has zero measure (normal tangent to the surfel or degenerate face)";
        throw InputError(os.str());
      }
    }
    if (s.dual) {
      s.points = mesh.face_centroids();
      s.mu = mu;
      s.ops.domain = Operators::Domain::Faces;
      if (s.tangent) s.normals = u;
    } else {
      // docs/math.md §6 PRIMAL: vertices, mu(v) = sum_{s ni v} mu(s)/4
      s.points = mesh.positions;
      s.mu = Eigen::VectorXd::Zero(mesh.num_vertices());
      for (int f = 0; f < F; ++f)
        for (int k = 0; k < 4; ++k) s.mu[mesh.faces(f, k)] += 0.25 * mu[f];
      for (int v = 0; v < mesh.num_vertices(); ++v)
        if (!(s.mu[v] > 0)) throw InputError("heat-kernel: vertex " + std::to_string(v) + " belongs to no face");
      s.ops.domain = Operators::Domain::Vertices;
    }
    return s;
  }
};

}  // namespace

std::unique_ptr<Discretization> make_heat_kernel() { return std::make_unique<HeatKernel>(); }

std::optional<LatticeHeatKernelPair> assemble_heat_kernel_lattice(const SurfelMesh& mesh, const NormalFields& normals,
                                                                  const Config& params, LatticeHeatKernel* recycle) {
  HeatKernel method;
  HeatKernel::Setup s = method.setup(mesh, normals, params);
  if (!s.dual || !s.symmetric || s.tangent) return std::nullopt;
  // Surfel centres are corners + h/2 in two axes: the lattice of step h/2 (up to rounding).
  std::optional<LatticeHeatKernel> L =
      LatticeHeatKernel::build(s.points, s.mu, s.t, s.cutoff, 0.5 * mesh.grid_step(), recycle);
  if (!L) return std::nullopt;
  return LatticeHeatKernelPair{std::move(*L), std::move(s.mu), std::move(s.ops.contract_risk)};
}

}  // namespace corrlap

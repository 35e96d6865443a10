#pragma once
// Heat-kernel Laplacian of Caissard et al. (docs/math.md §6; DGtal DiscreteExteriorCalculus::heatLaplace).
// Registry name "heat-kernel".
//
// The pointwise operator of docs/math.md §6 is, for a point set x_s with measures mu(s),
//   (A f)(s) = sum_{r != s, |x_r - x_s| < K sqrt(2t)} mu(r) / (4 pi t^2) exp(-|x_r - x_s|^2 / (4t)) (f(r) - f(s)).
// It is not symmetric, but A = diag(mu)^{-1} L with
//   L[s][r] = mu(s) mu(r) / (4 pi t^2) exp(-|x_r - x_s|^2 / (4t))  (s != r),  L[s][s] = -sum_{r != s} L[s][r],
// a symmetric negative semi-definite matrix (a graph Laplacian with positive weights). corrlap
// therefore returns, by default (mass = measure), L as above and M = diag(mu): M^{-1} L is exactly
// the pointwise operator, and the pair fits the same solvers, eigen problems and evaluation
// protocols as every other method (docs/math.md §0). With mass = identity it returns L = A and M = I.
//
// Assembly is sparse: a uniform grid of cell size K sqrt(2t) gives each point's neighbours from
// the 27 surrounding cells; columns are built independently in parallel (TBB) and written once
// into the CSC arrays, so the result is bitwise identical for any thread count.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <corrlap/core/discretization.hpp>
#include <corrlap/discretizations/heat_kernel_lattice.hpp>
#include <memory>
#include <optional>
#include <string>

namespace corrlap {

/// Diffusion time t = k h^alpha (docs/math.md §6; defaults k = 0.1, alpha = 2/3).
double heat_kernel_time(double h, double k = 0.1, double alpha = 2.0 / 3.0);

enum class HeatKernelForm {
  Symmetric,  ///< L = diag(mu) A (symmetric, negative semi-definite); pair with M = diag(mu)
  Pointwise,  ///< A itself: row s is the pointwise Laplacian at s (rows sum to 0)
};

/// Which entries of the matrix are stored.
enum class HeatKernelStorage {
  Full,   ///< every entry (what the registry returns; usable everywhere)
  Upper,  ///< Symmetric form only: entries with row <= column, half the memory. Use it through
          ///< Eigen's selfadjointView<Eigen::Upper>() (products, ConjugateGradient<..., Eigen::Upper>)
          ///< or CHOLMOD with stype = 1; every other consumer expects Full.
};

/// Sparse heat-kernel matrix on the points (rows of `points`) with measures `mu` > 0 (docs/math.md §6).
/// Only pairs closer than cutoff * sqrt(2t) are coupled. Throws InputError on bad sizes,
/// non-positive t/cutoff or Upper storage of the (non-symmetric) pointwise form, NumericalError
/// when the matrix would exceed 2^31 - 1 nonzeros or memory.
///
/// `tangent_normals` (optional, one unit normal per point) switches to the tangent-plane distance
/// (corrlap's extension, not in docs/math.md §6): the kernel uses |e|^2 - (e . n_rs)^2 with e = x_r - x_s and
/// n_rs the normalized mean of the two normals. Surfel centres lie up to ~h off the surface, and
/// this O(h^2 / t) error caps the backward order of the Euclidean kernel at 1; the tangent distance
/// removes it (order ~1.8 with t = h^1.75, docs/discretizations_extra.md). The cut-off still uses the
/// Euclidean distance.
Eigen::SparseMatrix<double> heat_kernel_matrix(const Eigen::MatrixX3d& points, const Eigen::VectorXd& mu, double t,
                                               double cutoff = 3.0, HeatKernelForm form = HeatKernelForm::Symmetric,
                                               HeatKernelStorage storage = HeatKernelStorage::Full,
                                               const Eigen::MatrixX3d* tangent_normals = nullptr);

/// Number of nonzeros heat_kernel_matrix would produce (same neighbour search, no values).
std::int64_t heat_kernel_nonzeros(const Eigen::MatrixX3d& points, double t, double cutoff = 3.0,
                                  HeatKernelStorage storage = HeatKernelStorage::Full);

/// The registered discretization. Parameters: t (default k h^alpha), k, alpha, cutoff,
/// distance = euclidean (docs/math.md §6, default) | tangent (see heat_kernel_matrix; dual variant only),
/// variant = dual (surfel values, domain Faces; default, as the reference) | primal (vertex
/// values, mu(v) = sum_{s ni v} mu(s)/4), mass = measure | identity, and the normal policy keys.
/// Needs one normal per face: mu(s) = (face area) |u_s . n_s| (h^2 |u_s . n_s| on surfels).
std::unique_ptr<Discretization> make_heat_kernel();

/// The registered method's pair with L in compact lattice form (heat_kernel_lattice.hpp): L equals
/// make_heat_kernel()->assemble(mesh, normals, params).L up to rounding, M = diag(mass).
struct LatticeHeatKernelPair {
  LatticeHeatKernel L;
  Eigen::VectorXd mass;       ///< the diagonal of M (#F)
  std::string contract_risk;  ///< as Operators::contract_risk
};

/// That pair for the parameters where it applies (variant = dual, mass = measure, distance =
/// euclidean, surfel centres on the lattice of step h/2: digitized surfaces), std::nullopt for any
/// other; throws what assemble() throws on bad parameters or normals.
/// `recycle`: as LatticeHeatKernel::build.
std::optional<LatticeHeatKernelPair> assemble_heat_kernel_lattice(const SurfelMesh& mesh, const NormalFields& normals,
                                                                  const Config& params,
                                                                  LatticeHeatKernel* recycle = nullptr);

}  // namespace corrlap

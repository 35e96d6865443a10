#include "patch_bias.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>
#include <string>
#include <vector>

namespace corrlap {

int patch_rings(double alpha, double step, const PatchBiasOptions& options) {
  if (!(alpha > 0.0) || !(step > 0.0) || !std::isfinite(alpha) || !std::isfinite(step))
    throw InputError("patch_rings: alpha and the step must be positive numbers");
  // The response of (L M^-1 L + alpha M) to a point load decays like exp(-alpha^(1/4) r / sqrt(2)).
  const double decay_steps = std::sqrt(2.0) / std::pow(alpha, 0.25) / step;
  const double rings = options.core_rings + options.rounds + std::ceil(options.margin_lengths * decay_steps);
  return int(std::min(rings, 1e9));
}

PatchBias patch_attachment_bias(const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>& faces,
                                const Eigen::SparseMatrix<double>& L, const Eigen::SparseMatrix<double>& M,
                                const Eigen::MatrixX3d& staircase, const Eigen::MatrixX3d& normals,
                                const Eigen::VectorXd& H, double alpha, double step, const PatchBiasOptions& options) {
  const Eigen::Index n = staircase.rows();
  if (L.rows() != n || L.cols() != n || M.rows() != n || M.cols() != n || normals.rows() != n || H.size() != n)
    throw InputError("patch_attachment_bias: L, M, the staircase, normals and H need one row per vertex (" +
                     std::to_string(n) + ")");
  if (options.patches < 1 || options.core_rings < 0 || options.rounds < 0 || !(options.margin_lengths >= 0.0))
    throw InputError("patch_attachment_bias: patches >= 1, core rings, rounds and margin >= 0");
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 4; ++k)
      if (faces(f, k) < 0 || faces(f, k) >= n)
        throw InputError("patch_attachment_bias: face " + std::to_string(f) + " has a vertex id out of range");
  PatchBias out;
  if (n == 0) return out;
  const int rings = patch_rings(alpha, step, options);
  const Eigen::VectorXd mass = M * Eigen::VectorXd::Ones(n);
  if (!(mass.array() > 0.0).all()) throw InputError("patch_attachment_bias: every vertex mass must be positive");
  const Eigen::MatrixX3d mismatch = L * staircase + 2.0 * (mass.asDiagonal() * (H.asDiagonal() * normals));

  // Faces by vertex, to collect a patch's faces without a pass over all of them.
  std::vector<Eigen::Index> face_start(std::size_t(n) + 1, 0), face_ids(std::size_t(4 * faces.rows()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) ++face_start[std::size_t(faces(f, k)) + 1];
  for (Eigen::Index v = 0; v < n; ++v) face_start[std::size_t(v) + 1] += face_start[std::size_t(v)];
  {
    std::vector<Eigen::Index> next(face_start.begin(), face_start.end() - 1);
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
      for (int k = 0; k < 4; ++k) face_ids[std::size_t(next[std::size_t(faces(f, k))]++)] = f;
  }

  // Per thread: the ring of each vertex in the current patch and its local id, -1 outside.
  struct Scratch {
    std::vector<int> depth, local;
  };
  tbb::enumerable_thread_specific<Scratch> scratch([n] {
    return Scratch{std::vector<int>(std::size_t(n), -1), std::vector<int>(std::size_t(n), -1)};
  });
  // Per patch, summed in order afterwards (the same sum whatever the threads).
  struct Result {
    double weighted = 0.0, weight = 0.0;
    Eigen::Index vertices = 0, core_vertices = 0;
  };
  std::vector<Result> results(std::size_t(options.patches));
  // Small independent solves: one per task, each factorized by Eigen's simplicial Cholesky (no BLAS,
  // whose threads CHOLMOD's supernodal kernels would fight over).
  Config eigen_solver;
  eigen_solver.set("solver", "eigen-llt");
  const auto solve_patch = [&](int k) {
    std::vector<int>& depth = scratch.local().depth;
    std::vector<int>& local = scratch.local().local;
    // Seeds spread over the vertex order, which follows the grid's scan on digital surfaces.
    const Eigen::Index seed = Eigen::Index((double(k) + 0.5) * double(n) / double(options.patches));
    // Breadth-first over L's graph (its exact zeros are no edges) up to `rings`.
    std::vector<Eigen::Index> patch{seed};
    depth[std::size_t(seed)] = 0;
    for (std::size_t head = 0; head < patch.size(); ++head) {
      const Eigen::Index v = patch[head];
      const int d = depth[std::size_t(v)];
      if (d == rings) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(L, v); it; ++it)
        if (it.value() != 0.0 && depth[std::size_t(it.index())] < 0) {
          depth[std::size_t(it.index())] = d + 1;
          patch.push_back(it.index());
        }
    }
    const Eigen::Index m = Eigen::Index(patch.size());
    for (Eigen::Index i = 0; i < m; ++i) local[std::size_t(patch[std::size_t(i)])] = int(i);

    // The displacement u = q - p on the patch, held at 0 outside it: L's principal submatrix, negative
    // semi-definite as L (a cut with the diagonal rebalanced need not be), and the curvature
    // mismatch r = L p + 2 M_l H n of the whole surface.
    std::vector<Eigen::Triplet<double>> entries;
    for (Eigen::Index i = 0; i < m; ++i)
      for (Eigen::SparseMatrix<double>::InnerIterator it(L, patch[std::size_t(i)]); it; ++it)
        if (const int j = local[std::size_t(it.index())]; j >= 0) entries.emplace_back(j, int(i), it.value());
    Eigen::SparseMatrix<double> L_patch(m, m);
    L_patch.setFromTriplets(entries.begin(), entries.end());
    Eigen::MatrixX3d p(m, 3), nrm(m, 3), r_over_m(m, 3);
    Eigen::VectorXd w(m), core_mass = Eigen::VectorXd::Zero(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      const Eigen::Index v = patch[std::size_t(i)];
      p.row(i) = staircase.row(v);
      nrm.row(i) = normals.row(v);
      r_over_m.row(i) = mismatch.row(v) / mass[v];
      w[i] = mass[v];
      if (depth[std::size_t(v)] <= options.core_rings) core_mass[i] = mass[v];
    }
    const Eigen::SparseMatrix<double> M_patch(w.asDiagonal());
    // Faces with every corner in the patch: each core vertex and its `rounds` rings have all theirs.
    std::vector<Eigen::Index> kept;
    for (Eigen::Index i = 0; i < m; ++i) {
      const Eigen::Index v = patch[std::size_t(i)];
      for (Eigen::Index s = face_start[std::size_t(v)]; s < face_start[std::size_t(v) + 1]; ++s) {
        const Eigen::Index f = face_ids[std::size_t(s)];
        bool inside = true;
        int lowest = int(m);
        for (int c = 0; c < 4; ++c) {
          const int j = local[std::size_t(faces(f, c))];
          inside = inside && j >= 0;
          lowest = std::min(lowest, j);
        }
        if (inside && lowest == int(i)) kept.push_back(f);  // once, from its lowest local corner
      }
    }
    Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> patch_faces(Eigen::Index(kept.size()), 4);
    for (std::size_t r = 0; r < kept.size(); ++r)
      for (int c = 0; c < 4; ++c) patch_faces(Eigen::Index(r), c) = local[std::size_t(faces(kept[r], c))];

    auto patch_solver = make_linear_solver(eigen_solver, kDefaultLinearSolver);
    // For q = p + u: (L M_l^-1 L + alpha M_l) q = alpha M_l p - L M_l^-1 (r - L p), with p the
    // attachment target (its positions also order the factorization).
    const Eigen::MatrixX3d g = -(L_patch * (r_over_m - w.cwiseInverse().asDiagonal() * (L_patch * p)));
    PreconditionedRegularization regularization(L_patch, M_patch, p, g, *patch_solver);
    const Eigen::MatrixX3d q = regularization.solve(alpha, options.accuracy * step);
    Result& result = results[std::size_t(k)];
    result.weight = core_mass.sum();
    result.weighted = attachment_bias(patch_faces, p, q, nrm, core_mass, step, options.rounds) * result.weight;
    result.vertices = m;
    result.core_vertices = (core_mass.array() > 0.0).count();
    for (const Eigen::Index v : patch) depth[std::size_t(v)] = local[std::size_t(v)] = -1;
  };
  // In rounds of every kBatches-th patch, each round spread over the whole vertex order, so that
  // the estimate after any round samples the whole surface.
  constexpr int kBatches = 4;
  for (int batch = 0; batch < std::min(kBatches, options.patches); ++batch) {
    const int count = (options.patches - batch + kBatches - 1) / kBatches;
    tbb::parallel_for(0, count, [&](int i) { solve_patch(batch + i * kBatches); });
    out.patches += count;
    double weighted = 0.0, weight = 0.0;
    out.vertices = out.core_vertices = 0;
    for (int k = 0; k < options.patches; ++k) {
      if (k % kBatches > batch) continue;
      const Result& result = results[std::size_t(k)];
      weighted += result.weighted;
      weight += result.weight;
      out.vertices += result.vertices;
      out.core_vertices += result.core_vertices;
    }
    out.bias = weight > 0.0 ? weighted / weight : 0.0;
    if (out.bias < options.stop_below) break;
  }
  return out;
}

}  // namespace corrlap

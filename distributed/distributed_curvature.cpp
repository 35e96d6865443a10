#include "distributed_curvature.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/estimators/corrected_curvature.hpp>
#include <string>

namespace corrlap {

int curvature_halo_columns(double r, double spacing, double h) {
  if (!(r > 0.0) || !std::isfinite(r) || !(spacing >= 0.0) || !std::isfinite(spacing) || !(h > 0.0) ||
      !std::isfinite(h))
    throw InputError(
        "distributed curvature: the radius and step must be positive and finite, the spacing "
        "non-negative and finite (got r = " +
        std::to_string(r) + ", spacing = " + std::to_string(spacing) + ", h = " + std::to_string(h) + ")");
  // In columns: sites within `spacing` of a vertex, their cells' vertices within 2 spacing more,
  // their balls' faces within r of the site; + 1 for a face's extent, + 1 for its corners' fans,
  // + 1 for the half column between a position and its pointel.
  const double reach = std::max(r + spacing, 3.0 * spacing) / h;
  if (!(reach < 1e8))
    throw InputError("distributed curvature: a reach of " + std::to_string(reach) + " columns is absurd");
  return int(std::ceil(reach)) + 3;
}

Eigen::VectorXd distributed_mean_curvature(const DistributedSurface& surface, const NearSlabNormals& near, double r,
                                           double spacing) {
  const int needed = curvature_halo_columns(r, spacing, surface.mesh.h);
  if (near.columns < needed)
    throw InputError("distributed curvature: the surface near the slab spans " + std::to_string(near.columns) +
                     " columns, the radius and spacing need " + std::to_string(needed));
  // A slab the surface does not cross has no vertex to estimate (and the estimator no mesh).
  if (surface.num_owned == 0) return Eigen::VectorXd();
  const CorrectedCurvature measures = CorrectedCurvature::interpolated(near.mesh, near.vertex_normals);
  const Eigen::VectorXd H = measures.mean_curvature_at_sites(r, spacing, near.owned_vertices).H;
  Eigen::VectorXd out(surface.num_owned);
  for (int v = 0; v < surface.num_owned; ++v) out[v] = H[near.owned_vertices[std::size_t(v)]];
  return out;
}

}  // namespace corrlap

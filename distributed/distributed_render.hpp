#pragma once
// Pictures of the distributed front end's surfaces without gathering them (docs/distributed.md,
// "Writing the outputs"): every rank draws its own faces in the frame of the whole surface, and the
// samples are merged towards rank 0 (render/render_mesh.hpp's pieces). The picture is render_mesh's
// of the gathered surface, byte for byte.
#include <Eigen/Core>
#include <corrlap/render/render_mesh.hpp>
#include <optional>
#include <string>

#include "distributed_surface.hpp"

namespace corrlap {

/// field_percentiles of the values of every rank (#owned each, one per owned vertex): the same
/// order statistics, found by bisection on counts over the ranks. `name` is the field's in errors:
/// InputError on every rank when there is no value or a value is not finite (naming the vertex's
/// serial id). Collective.
FieldPercentiles distributed_field_percentiles(const DistributedSurface& s, const std::string& name,
                                               const Eigen::VectorXd& owned_values);

/// render_mesh of the whole surface with its owned vertices at `positions` (#owned by 3), coloured
/// by `values` at the owned vertices (#owned) in `scale` under the title `name`, or grey without a
/// scale (the same on every rank; `values` then unread). The picture on rank 0, an empty Image on
/// the others. Collective.
Image distributed_render(const DistributedSurface& s, const Eigen::MatrixX3d& positions, const std::string& name,
                         const Eigen::VectorXd& values, const std::optional<ColourScale>& scale,
                         const RenderOptions& options);

}  // namespace corrlap

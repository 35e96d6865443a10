#pragma once
// The defaults that depend on what a loaded surface came from, decided here once for every front
// end (CLI, Python, studies): the curvature radius, as resolve_normals decides the II radius
// (default_ii_params) from the same information.
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <optional>

namespace corrlap {

/// Whether the surface is made of voxels from a file or an array (a volume, a voxelized mesh file):
/// voxels and no implicit shape. Implicit shapes and quad meshes given as they are are not.
bool voxels_from_file(const LoadedSurface& surface);

/// default_curvature_radius of the surface: 0.1 size (`size` unset: regularization_size of its mesh),
/// for voxels from a file at least kVoxelMinCurvatureRadius voxels.
double default_curvature_radius(const LoadedSurface& surface, std::optional<double> size = {});

/// regularization_curvature and regularize_surface on a loaded surface: the options' curvature
/// radius, when unset, is the surface's default_curvature_radius (with the options' size).
RegularizationCurvature regularization_curvature(const LoadedSurface& surface, const NormalFields& normals,
                                                 const RegularizationOptions& options = {});
RegularizedSurface regularize_surface(const LoadedSurface& surface, const NormalFields& normals,
                                      const RegularizationOptions& options = {},
                                      const RegularizationCurvature* curvature = nullptr);

}  // namespace corrlap

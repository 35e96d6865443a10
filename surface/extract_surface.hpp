#pragma once
// Voxels -> digital surface (docs/math.md §1.3, §1.4): the boundary of a voxel set as a quad mesh of
// surfels, numbered exactly like the reference.
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <string>
#include <vector>

namespace corrlap {

/// Surface of a voxel set (docs/math.md §1.3) as a quad mesh numbered exactly like the reference (§1.4):
/// faces sorted by (positive, kc_x, kc_y, kc_z), vertices numbered in order of first appearance.
/// Surfels exist only between two voxels of the box. Throws InputError if there is no surfel.
SurfelMesh extract_surface(const VoxelGrid& grid);

/// Time spent in each phase of extract_surface, in order (for benchmarks): wall-clock seconds and
/// CPU seconds of the whole process (all threads; on a shared machine the CPU time shows the work
/// even when the wall-clock time is inflated by other processes).
struct PhaseTimings {
  struct Phase {
    std::string name;
    double wall_seconds = 0.0;
    double cpu_seconds = 0.0;
  };
  std::vector<Phase> phases;
};
/// extract_surface recording its phase times into `timings` (may be null).
SurfelMesh extract_surface(const VoxelGrid& grid, PhaseTimings* timings);

}  // namespace corrlap

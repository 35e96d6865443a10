// The curvature radius default is decided once, from what the surface came from (pipeline/
// surface_defaults.hpp): the paper's 0.1 size for implicit shapes and meshes given as they are, at
// least kVoxelMinCurvatureRadius voxels for volumes. tests/python/test_volumes.py checks that the
// CLI and Python use it.
#include <doctest/doctest.h>

#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_defaults.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <vector>

using namespace corrlap;

namespace {

// A ball of radius 4 voxels in a 12^3 array: 0.1 size is about 0.45 voxel, below the floor.
std::vector<double> small_ball() {
  std::vector<double> v(12 * 12 * 12, 0.0);
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y)
      for (int z = 0; z < 12; ++z) {
        const double dx = x - 5.5, dy = y - 5.5, dz = z - 5.5;
        if (dx * dx + dy * dy + dz * dz <= 16.0) v[std::size_t((x * 12 + y) * 12 + z)] = 1.0;
      }
  return v;
}

}  // namespace

TEST_CASE("default curvature radius: the paper's 0.1 size for shapes and given meshes, a floor in voxels for volumes") {
  CHECK(default_curvature_radius(1.0, 0.1, false) == 0.1);
  CHECK(default_curvature_radius(1.0, 0.1, true) == kVoxelMinCurvatureRadius * 0.1);
  CHECK(default_curvature_radius(100.0, 0.1, true) == doctest::Approx(10.0));  // 0.1 size above the floor
  CHECK(default_curvature_radius(1.0, 0.1, false, 0.2) == 0.2);

  const std::vector<double> values = small_ball();
  const LoadedSurface volume = load_surface(VolumeArrayInput::c_order(values, Eigen::Vector3i(12, 12, 12)));
  CHECK(voxels_from_file(volume));
  REQUIRE(0.1 * regularization_size(volume.mesh) < kVoxelMinCurvatureRadius * volume.h);
  CHECK(default_curvature_radius(volume) == kVoxelMinCurvatureRadius * volume.h);
  CHECK(default_curvature_radius(volume, 100.0) == doctest::Approx(10.0));  // a given size

  ImplicitShapeInput shape_input;
  shape_input.shape = "sphere1";
  shape_input.digitization.h = 0.2;
  const LoadedSurface shape = load_surface(shape_input);
  CHECK(!voxels_from_file(shape));
  CHECK(default_curvature_radius(shape) == 0.1 * regularization_size(shape.mesh));  // below 2 h, kept

  QuadMeshInput given;
  given.mesh = shape.mesh;
  const LoadedSurface mesh = load_surface(given);
  CHECK(!voxels_from_file(mesh));
  CHECK(default_curvature_radius(mesh) == default_curvature_radius(shape));
}

TEST_CASE("regularize_surface on a loaded surface uses its default curvature radius, a given one replaces it") {
  const std::vector<double> values = small_ball();
  const LoadedSurface volume = load_surface(VolumeArrayInput::c_order(values, Eigen::Vector3i(12, 12, 12)));
  const NormalFields n = resolve_normals(volume, NormalKind::Vertex, NormalRequest{});
  const RegularizedSurface r = regularize_surface(volume, n, RegularizationOptions{});
  CHECK(r.curvature_radius == kVoxelMinCurvatureRadius * volume.h);
  RegularizationOptions given;
  given.curvature_radius = kVoxelMinCurvatureRadius * volume.h;
  // The mesh alone does not know its voxels came from an array: the paper's rule unless given.
  CHECK(regularization_curvature(volume.mesh, n, RegularizationOptions{}).curvature_radius ==
        doctest::Approx(0.1 * regularization_size(volume.mesh)));
  CHECK(regularize_surface(volume.mesh, n, given).mesh.positions == r.mesh.positions);
  given.curvature_radius = 3.0 * volume.h;
  CHECK(regularization_curvature(volume, n, given).curvature_radius == 3.0 * volume.h);

  ImplicitShapeInput shape_input;
  shape_input.shape = "sphere1";
  shape_input.digitization.h = 0.2;
  const LoadedSurface shape = load_surface(shape_input);
  const NormalFields t = resolve_normals(shape, NormalKind::Vertex, NormalRequest{});
  const RegularizedSurface s = regularize_surface(shape, t, RegularizationOptions{});
  CHECK(s.curvature_radius == 0.1 * regularization_size(shape.mesh));
  CHECK(s.mesh.positions == regularize_surface(shape.mesh, t, RegularizationOptions{}).mesh.positions);
}

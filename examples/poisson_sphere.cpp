// Poisson problem on the digitized unit sphere: voxels -> surface -> II normals -> corrected FEM ->
// L g = M b with CHOLMOD (docs/math.md §10.4), b = Laplacian of f = x^2 (docs/math.md §10.2); prints the errors.
#include <corrlap/corrlap.hpp>
#include <cstdio>

int main() {
  using namespace corrlap;
  const VoxelGrid voxels = digitize(make_implicit_shape("sphere1"), {.h = 0.1, .min_aabb = -1.5, .max_aabb = 1.5});
  const SurfelMesh mesh = extract_surface(voxels);
  const Eigen::MatrixX3d normals = ii_face_normals(voxels, mesh);  // integral invariant, docs/math.md §7
  const Operators ops = corrected_fem(mesh, normals);              // L, M: #V x #V, L <= 0
  auto solver = make_linear_solver("cholmod");
  const PoissonResult r = solve_poisson(ops, mesh.positions, test_function("x2"), *solver);
  std::printf("%d vertices: error L_inf %.4g, L2 %.4g\n", mesh.num_vertices(), r.errors.linf, r.errors.l2);
  // Measured 0.0152 / 0.00524; trivial normals give 0.136 (L2), uncorrected PolyDEC 0.128, h = 0.2 0.0104.
  return r.errors.linf < 0.03 && r.errors.l2 < 0.01 ? 0 : 1;
}

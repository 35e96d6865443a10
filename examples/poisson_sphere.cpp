// Poisson problem on the digitized unit sphere: voxels -> surface -> II normals -> corrected FEM ->
// L g = M b with CHOLMOD (spec §10.4), b = Laplacian of f = x^2 (spec §10.2); prints the errors.
#include <corrlap/corrlap.hpp>

#include <cstdio>

int main() {
  using namespace corrlap;
  const VoxelGrid voxels = digitize(make_implicit_shape("sphere1"), {.h = 0.1, .min_aabb = -1.5, .max_aabb = 1.5});
  const SurfelMesh mesh = extract_surface(voxels);
  const Eigen::MatrixX3d normals = ii_face_normals(voxels, mesh);  // integral invariant, spec §7
  const Operators ops = corrected_fem(mesh, normals);              // L, M: #V x #V, L <= 0
  auto solver = make_linear_solver("cholmod");
  const PoissonResult r = solve_poisson(ops, mesh.positions, test_function("x2"), *solver);
  std::printf("%d vertices: error L_inf %.4g, L2 %.4g\n", mesh.num_vertices(), r.errors.linf, r.errors.l2);
  return r.errors.l2 < 0.02 ? 0 : 1;  // bound: see the report
}

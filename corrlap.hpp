#pragma once
// corrlap: corrected Laplace-Beltrami operators for digital surfaces. The one header a user needs:
//   #include <corrlap/corrlap.hpp>
// and link corrlap::corrlap. From voxels to a Poisson solve (examples/poisson_sphere.cpp):
//   VoxelGrid voxels = digitize(make_implicit_shape("sphere1"), {.h = 0.1, .min_aabb = -1.5, .max_aabb = 1.5});
//   SurfelMesh mesh = extract_surface(voxels);
//   Operators ops = corrected_fem(mesh, ii_face_normals(voxels, mesh));   // L #V x #V, negative semi-definite
//   auto solver = make_linear_solver("cholmod");
//   PoissonResult r = solve_poisson(ops, mesh.positions, test_function("x2"), *solver);
// Sign convention everywhere: L 1 = 0, u^T L u <= 0, eigenvalues of L u = lambda M u are <= 0.
// Only installed headers are included here (no detail/).

// Data and contracts.
#include <corrlap/core/config.hpp>
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/linear_solver.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/parameters.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/core/voxel_grid.hpp>

// Voxels -> digital surface.
#include <corrlap/surface/closest_point.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <corrlap/surface/loop_subdivision.hpp>
#include <corrlap/surface/mesh_voxelization.hpp>

// Files: meshes, volumes, normals, scalars, Matrix Market.
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>

// Normals and curvature.
#include <corrlap/estimators/corrected_curvature.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <corrlap/estimators/normal_estimation.hpp>
#include <corrlap/estimators/normal_resolution.hpp>

// The pipeline's first steps, one way for every front end: a surface input loaded, checked, its normals.
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_checks.hpp>

// Operators: one free function per method, the registry, and the triangle-mesh cotan / heat time.
#include <corrlap/discretizations/cotan.hpp>
#include <corrlap/discretizations/heat_kernel.hpp>
#include <corrlap/discretizations/methods.hpp>
#include <corrlap/discretizations/registry.hpp>

// Linear and eigen solvers.
#include <corrlap/backends/registry.hpp>

// Problems: test functions of docs/math.md §10.2, Poisson (backward) and forward evaluation.
#include <corrlap/problems/problems.hpp>
#include <corrlap/problems/test_functions.hpp>

// Regularization: positions from the corrected Laplacian and Delta p = -2 H n (paper §4.1).
#include <corrlap/regularization/attachment_bias.hpp>
#include <corrlap/regularization/curvature_editing.hpp>
#include <corrlap/regularization/laplacian_regularization.hpp>
#include <corrlap/regularization/normal_map_reconstruction.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <corrlap/regularization/solution_check.hpp>
#include <corrlap/regularization/surface_quality.hpp>

// Pictures: a headless z-buffer rendering of a surface with a colour map, written as PNG.
#include <corrlap/render/image.hpp>
#include <corrlap/render/render_mesh.hpp>

#pragma once
// One free function per discretization, in the style of libigl: mesh and normals in, operators
// out. Each is the registry path make_discretization(name)->assemble(mesh, normals, options), bit
// for bit; use the registry to pick a method at run time.
//
// Every function returns Operators with
//   L  #V by #V stiffness, symmetric NEGATIVE semi-definite: L 1 = 0, u^T L u <= 0 (docs/math.md §0);
//   M  #V by #V mass, symmetric positive definite for consistent normals;
// so that M^{-1} L approximates the Laplace-Beltrami operator and the eigenvalues of L u = lambda M u
// are <= 0. The heat kernel's default variant lives on faces (#F by #F, domain Faces).
// `mesh` is a SurfelMesh with #V vertices and #F quads; face normals are #F by 3, vertex normals
// #V by 3, unit length and consistent with the surfel orientation (u . n_triv > 0; the option
// "orientation" = error | warn | clamp says what to do otherwise, "normalize" = true rescales).
// `options` are the method's parameters (Config::from_key_values({"lambda=0.5"})); unknown keys are
// InputErrors listing the valid ones (`corrlap operators --help`, docs/discretizations.md).
#include <Eigen/Core>
#include <corrlap/core/config.hpp>
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <string>

namespace corrlap {

/// Any registered method by name (fem, interpolated, polydec, projected-polydec, vrm, corrected-vrm,
/// heat-kernel, cotan) with the normals it needs (Discretization::required_normals()).
Operators assemble_operators(const std::string& method, const SurfelMesh& mesh, const NormalFields& normals,
                             const Config& options = {});

/// Corrected FEM (docs/math.md §4, "fem"): bilinear quads corrected by one normal per face.
/// Options: mass = full (default) | lumped.
Operators corrected_fem(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Config& options = {});

/// Interpolated corrected calculus (docs/math.md §3, "interpolated"): bilinearly interpolated vertex
/// normals. Options: lambda (0.1), kappa (2), assembly = global (default) | local, extras (D0,
/// sharp, flat, M1).
Operators interpolated(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals, const Config& options = {});

/// PolyDEC of de Goes et al. (docs/math.md §2.1-§2.4, "polydec"), uncorrected: needs no normals and does
/// not converge on digital surfaces (the paper's baseline). Options: lambda (1), extras.
Operators polydec(const SurfelMesh& mesh, const Config& options = {});

/// Projected PolyDEC (docs/math.md §2.5, "projected-polydec"): corners projected on the face normal's plane.
/// Options: lambda (1), extras.
Operators projected_polydec(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Config& options = {});

/// Virtual refinement of Bunge et al. (docs/math.md §5.1, "vrm"), uncorrected baseline. Options: mass.
Operators vrm(const SurfelMesh& mesh, const Config& options = {});

/// Corrected virtual refinement (docs/math.md §5.2, "corrected-vrm") with vertex normals. Options: mass,
/// max_iterations, gradient_tolerance.
Operators corrected_vrm(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals, const Config& options = {});

/// Heat-kernel Laplacian of Caissard et al. (docs/math.md §6, "heat-kernel"). Default variant dual: L and
/// M are #F by #F on surfel centres (domain Faces), M = diag(mu); variant=primal gives #V by #V.
/// Options: t (or k, alpha), cutoff, distance, variant, mass = measure | identity.
Operators heat_kernel(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals, const Config& options = {});

/// Cotan Laplacian on the quads split into triangles ("cotan"), lumped mass. Options: mass =
/// voronoi (default) | barycentric.
Operators cotan(const SurfelMesh& mesh, const Config& options = {});

}  // namespace corrlap

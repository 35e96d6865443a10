#pragma once
// Shared pieces of the quad-based discretizations (PolyDEC, interpolated corrected calculus,
// corrected FEM): local difference operator, assembly plans over faces, global D0, and the
// global sharp/flat/M1 layouts of docs/math.md §2.3 and §3.6.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <corrlap/core/config.hpp>
#include <corrlap/core/mesh_topology.hpp>
#include <corrlap/core/parameters.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/discretizations/assembly/parallel_assembly.hpp>
#include <string>

namespace corrlap {

/// Corners x0..x3 of a quad as rows (docs/math.md §0 order).
using QuadCorners = Eigen::Matrix<double, 4, 3, Eigen::RowMajor>;
/// Local per-face 3x4 (sharp) and 4x3 (flat) matrices.
using QuadSharp = Eigen::Matrix<double, 3, 4>;
using QuadFlat = Eigen::Matrix<double, 4, 3>;

/// Corners of face f.
QuadCorners quad_corners(const SurfelMesh& mesh, int f);
/// Corner rows of a per-vertex field for face f.
QuadCorners quad_corner_rows(const SurfelMesh& mesh, const Eigen::MatrixX3d& field, int f);

/// Local difference D (docs/math.md §0): row i has -1 at column i and +1 at column i+1 (mod 4).
const Eigen::Matrix4d& quad_difference();

/// Plan for vertex-based 4x4 face matrices (A[v_i, v_j] += A_f[i, j]).
AssemblyPlan quad_vertex_plan(const SurfelMesh& mesh);
/// Plan for diagonal matrices assembled from one value per face corner (element = face corner).
AssemblyPlan quad_corner_diagonal_plan(const SurfelMesh& mesh);
/// Plan for edge-based 4x4 face matrices with the edge signs of docs/math.md §0.
AssemblyPlan quad_edge_plan(const EdgeTopology& topology);

/// #E x #V exterior derivative: row e has -1 at its first (smaller) vertex, +1 at the second.
Eigen::SparseMatrix<double> global_d0(const EdgeTopology& topology, int num_vertices);

/// Global sharp (3#F x #E, rows 3f+c, entries s_{f,i} U_f[c,i]) from per-face 3x4 blocks
/// (`sharp` holds 12 values per face, column-major 3x4). docs/math.md §3.6(a), §2.3.
Eigen::SparseMatrix<double> global_sharp(const EdgeTopology& topology, const double* sharp);
/// Global flat (#E x 3#F, entries s_{f,i} V_f[i,c] / (faces of e)) from per-face 4x3 blocks
/// (`flat` holds 12 values per face, column-major 4x3).
Eigen::SparseMatrix<double> global_flat(const EdgeTopology& topology, const double* flat);

/// Diagonal matrix of the row sums of A (row-sum lumping).
Eigen::SparseMatrix<double> row_sum_lumped(const Eigen::SparseMatrix<double>& A);

/// SurfelMesh::validate(what) with the checks run in parallel (same exceptions and messages).
void validate_mesh(const SurfelMesh& mesh, const char* what);
/// Throws InputError when the mesh is empty or invalid (context names the method).
void check_quad_mesh(const SurfelMesh& mesh, const std::string& method);

/// The parameter "extras" (build D0, sharp, flat, M1 and M_lumped besides L and M).
Parameter extras_parameter();

}  // namespace corrlap

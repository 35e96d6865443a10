#pragma once
// Fast assembly of the corrected FEM (corrected_fem_fast.cpp), bitwise equal to the readable local
// matrices of corrected_fem.hpp (docs/math.md §4.2-§4.4). Internal header.
#include <Eigen/Core>
#include <corrlap/core/discretization.hpp>
#include <corrlap/discretizations/assembly/detail/face_kernel_isa.hpp>
#include <cstddef>

namespace corrlap::detail {

/// Values per face written by fem_face_range: the six distinct entries of K_f
/// (self, o1, o2, o, self - 2 eta, o + 2 eta; docs/math.md §4.3 pattern) and the mass scales
/// area z / 36 and area z / 4 (docs/math.md §4.4).
inline constexpr std::size_t kFemFaceValues = 8;

/// Values of faces [b, e) into g + kFemFaceValues f. `positions` (V x 3) and `normals` (F x 3,
/// face normals) are column-major; `faces` holds 4 vertex ids per face. The vector paths compute
/// one face per lane with the scalar operations, so every ISA gives the same bits.
void fem_face_range(const double* positions, std::size_t num_vertices, const int* faces, const double* normals,
                    std::size_t num_faces, int b, int e, double* g, FaceKernelIsa isa = FaceKernelIsa::Best);

/// ops.L = sum_f L_f = -sum_f K_f and ops.M (consistent, or lumped when `lumped`) for face normals u
/// (#F x 3), through `pattern` when given; also ops.M_lumped when `with_lumped`.
void corrected_fem_fast_assembly(const SurfelMesh& mesh, const Eigen::MatrixX3d& u, const QuadPattern* pattern,
                                 bool lumped, bool with_lumped, Operators& ops);

}  // namespace corrlap::detail

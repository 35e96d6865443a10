#pragma once
// Run-time choice of the instruction set for the per-face assembly kernels (interpolated_kernel,
// fem_kernel). Internal header. The vector versions compute one face per SIMD lane with exactly the
// scalar operations in the same order and no FMA contraction (-ffp-contract=off, CMakeLists.txt),
// so every choice gives the same bits.

namespace corrlap::detail {

/// Best picks AVX2 when the CPU has it, else two lanes (SSE2 on x86-64, the target's 128-bit
/// vectors elsewhere). Avx2 exists only on x86.
enum class FaceKernelIsa { Best, Scalar, Sse2, Avx2 };

/// True when the running CPU supports AVX2 (FaceKernelIsa::Avx2 may then be requested).
bool cpu_has_avx2();

/// Throws std::logic_error when `isa` is Avx2 and the CPU lacks it; returns Avx2 or Sse2 for Best.
FaceKernelIsa resolve_face_kernel_isa(FaceKernelIsa isa);

}  // namespace corrlap::detail

#include "face_kernel_isa.hpp"

#include <stdexcept>

namespace corrlap::detail {

bool cpu_has_avx2() {
#if defined(__x86_64__) || defined(__i386__)
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}

FaceKernelIsa resolve_face_kernel_isa(FaceKernelIsa isa) {
  if (isa == FaceKernelIsa::Best) return cpu_has_avx2() ? FaceKernelIsa::Avx2 : FaceKernelIsa::Sse2;
  if (isa == FaceKernelIsa::Avx2 && !cpu_has_avx2()) throw std::logic_error("face kernel: this CPU has no AVX2");
  return isa;
}

}  // namespace corrlap::detail

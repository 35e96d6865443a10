// libFuzzer target: NIfTI-1 and NIfTI-2 volumes, plain or gzip (io/nifti.cpp).
#include <corrlap/io/volume_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".nii");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume_data(path); });
  return 0;
}

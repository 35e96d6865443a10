// libFuzzer target: raw uint8 volumes (io/volume_io.cpp). The first three bytes choose the
// dimensions (1..256 each), the rest is the file.
#include <corrlap/io/volume_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  corrlap::VolumeReadOptions options;
  options.raw_dimensions = Eigen::Vector3i(int(data[0]) + 1, int(data[1]) + 1, int(data[2]) + 1);
  const std::string path = corrlap::fuzz::write_input(data + 3, size - 3, ".raw");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume(path, options); });
  return 0;
}

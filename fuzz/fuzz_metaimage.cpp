// libFuzzer target: MetaImage volumes with LOCAL data, raw or zlib (io/metaimage.cpp).
#include <corrlap/io/volume_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".mha");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume_data(path); });
  return 0;
}

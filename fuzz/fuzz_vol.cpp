// libFuzzer target: DGtal .vol volumes (io/volume_io.cpp).
#include <corrlap/io/volume_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".vol");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume(path); });
  return 0;
}

// libFuzzer target: OFF meshes (io/off.cpp).
#include <corrlap/io/mesh_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".off");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_mesh(path); });
  return 0;
}

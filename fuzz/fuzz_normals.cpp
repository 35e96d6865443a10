// libFuzzer target: normal files, one nx ny nz per line (io/text_io.cpp).
#include <corrlap/io/text_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".txt");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_normals(path); });
  return 0;
}

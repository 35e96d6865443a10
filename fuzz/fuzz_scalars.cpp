// libFuzzer target: scalar files, one value per line (io/text_io.cpp).
#include <corrlap/io/text_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".txt");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_scalars(path); });
  return 0;
}

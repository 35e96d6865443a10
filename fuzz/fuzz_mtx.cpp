// libFuzzer target: Matrix Market matrices (io/text_io.cpp).
#include <corrlap/io/text_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".mtx");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_matrix_market(path); });
  return 0;
}

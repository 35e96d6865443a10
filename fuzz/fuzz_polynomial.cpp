// libFuzzer target: the polynomial parser (surface/polynomial.cpp), then one evaluation.
#include <corrlap/surface/polynomial.hpp>
#include <string_view>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  corrlap::fuzz::expect_named_errors([&] {
    const auto p = corrlap::Polynomial::parse(std::string_view(reinterpret_cast<const char*>(data), size));
    (void)p(0.25, -0.5, 0.75);
  });
  return 0;
}

// libFuzzer target: JSON configurations (core/config.cpp), read through every typed getter.
#include <corrlap/core/config.hpp>
#include <string_view>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  corrlap::fuzz::expect_named_errors([&] {
    const auto config = corrlap::Config::from_json_string(std::string_view(reinterpret_cast<const char*>(data), size));
    for (const auto& key : config.keys()) {
      corrlap::fuzz::expect_named_errors([&] { (void)config.get_double(key, 0.0); });
      corrlap::fuzz::expect_named_errors([&] { (void)config.get_int(key, 0); });
      corrlap::fuzz::expect_named_errors([&] { (void)config.get_bool(key, false); });
      corrlap::fuzz::expect_named_errors([&] { (void)config.get_string(key, ""); });
    }
  });
  return 0;
}

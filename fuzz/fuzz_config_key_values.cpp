// libFuzzer target: key=value configurations (core/config.cpp); lines of the input are the items.
#include <corrlap/core/config.hpp>
#include <string>
#include <vector>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> items(1);
  for (std::size_t i = 0; i < size; ++i) {
    if (data[i] == '\n')
      items.emplace_back();
    else
      items.back() += char(data[i]);
  }
  corrlap::fuzz::expect_named_errors([&] {
    const auto config = corrlap::Config::from_key_values(items);
    // The getters parse one value at a time, so a few keys per input reach all of their code;
    // probing every key of a long input (three throws each under ASan) only slows the search.
    constexpr std::size_t probed_keys = 8;
    std::size_t probed = 0;
    for (const auto& key : config.keys()) {
      if (++probed > probed_keys) break;
      corrlap::fuzz::expect_named_errors([&] { (void)config.get_double(key, 0.0); });
      corrlap::fuzz::expect_named_errors([&] { (void)config.get_int(key, 0); });
      corrlap::fuzz::expect_named_errors([&] { (void)config.get_bool(key, false); });
    }
  });
  return 0;
}

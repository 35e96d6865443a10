// libFuzzer target: multi-page TIFF stacks (io/tiff.cpp, through libtiff), read in their own type
// and streamed into a voxel grid.
#include <corrlap/core/memory_budget.hpp>
#include <corrlap/io/volume_io.hpp>
#include <cstdlib>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // A compressed page may decode to 65536 times its bytes: a budget keeps such announced volumes
  // within the fuzzer's memory limit (they are refused, named, as on a small machine). A smaller
  // CORRLAP_MAX_MEMORY (fuzz_support.hpp) is kept.
  static const bool budget =
      std::getenv("CORRLAP_MAX_MEMORY") || (corrlap::set_memory_budget(std::uint64_t{256} << 20), true);
  (void)budget;
  const std::string path = corrlap::fuzz::write_input(data, size, ".tif");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume_data(path); });
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume_as_voxels(path, {}); });
  return 0;
}

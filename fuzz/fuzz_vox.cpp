// libFuzzer target: MagicaVoxel .vox volumes (io/magicavoxel.cpp): chunks, sparse voxels, read in their own type and
// streamed into a voxel grid.
#include <corrlap/io/volume_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = corrlap::fuzz::write_input(data, size, ".vox");
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume_data(path); });
  corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume_as_voxels(path, {}); });
  return 0;
}

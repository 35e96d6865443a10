// libFuzzer target: DGtal .vol and .longvol volumes (io/volume_io.cpp), the same bytes read as both,
// as bytes and streamed into a voxel grid.
#include <corrlap/io/volume_io.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  corrlap::VolumeReadOptions thresholded;
  thresholded.inside = corrlap::InsideRule::above(127.0);
  thresholded.h = 0.0;
  for (const char* extension : {".vol", ".longvol"}) {
    const std::string path = corrlap::fuzz::write_input(data, size, extension);
    corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume(path); });
    corrlap::fuzz::expect_named_errors([&] { (void)corrlap::read_volume_as_voxels(path, thresholded); });
  }
  return 0;
}

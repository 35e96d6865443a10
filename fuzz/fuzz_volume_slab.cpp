// libFuzzer target: volumes read per slab (read_volume_voxel_box, read_volume_slab_as_voxels,
// io/volume_io.cpp). The first byte picks the format, the second and third a range of x; the rest
// is the file. Beyond "no crash, named errors only", a slab that reads must hold exactly the whole
// read's voxels of its columns: a difference aborts (a finding).
#include <corrlap/io/volume_io.hpp>
#include <cstdlib>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const char* const kExtensions[] = {".vol", ".longvol", ".nrrd", ".nii", ".nii.gz", ".npy",
                                            ".mha", ".binvox",  ".vox",  ".tif", ".raw"};
  constexpr std::size_t kFormats = sizeof(kExtensions) / sizeof(kExtensions[0]);
  if (size < 3) return 0;
  const char* extension = kExtensions[data[0] % kFormats];
  const int from = int(data[1]) - 128, width = int(data[2] % 16);
  const std::string path = corrlap::fuzz::write_input(data + 3, size - 3, extension);
  corrlap::VolumeReadOptions options;
  options.inside = corrlap::InsideRule::above(127.0);
  options.h = 0.0;
  options.centered = (data[1] & 1) != 0;
  options.raw_dimensions = Eigen::Vector3i(4, 4, 4);
  corrlap::fuzz::expect_named_errors([&] {
    const corrlap::VolumeVoxelBox box = corrlap::read_volume_voxel_box(path, options);
    const int first = box.lower.x() + from % (box.upper.x() - box.lower.x() + 2);
    const corrlap::VoxelGrid slab = corrlap::read_volume_slab_as_voxels(path, options, first, first + width);
    corrlap::VoxelGrid whole;
    try {
      whole = corrlap::read_volume_as_voxels(path, options);
    } catch (const corrlap::InputError&) {
      // An empty volume: the slab must be empty too.
      if (slab.count() != 0) std::abort();
      return;
    }
    if (whole.lower().y() != slab.lower().y() || whole.upper().z() != slab.upper().z() || whole.h() != slab.h())
      std::abort();
    for (int z = slab.lower().z(); z <= slab.upper().z(); ++z)
      for (int y = slab.lower().y(); y <= slab.upper().y(); ++y)
        for (int x = slab.lower().x(); x <= slab.upper().x(); ++x)
          if (slab.get(x, y, z) != whole.get(x, y, z)) std::abort();
  });
  return 0;
}

// MagicaVoxel volumes (io/detail/volume_readers.hpp). Not written yet: every call is a named error.
#include <corrlap/io/detail/volume_readers.hpp>

namespace corrlap::io_detail {

void read_magicavoxel(const std::string& path, VoxelSink&) { fail(path, "MagicaVoxel files cannot be read yet"); }

}  // namespace corrlap::io_detail

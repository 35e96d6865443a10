// binvox volumes (io/detail/volume_readers.hpp). Not written yet: every call is a named error.
#include <corrlap/io/detail/volume_readers.hpp>

namespace corrlap::io_detail {

void read_binvox(const std::string& path, VoxelSink&) { fail(path, "binvox files cannot be read yet"); }
void write_binvox(const std::string& path, const VolumeData&) { fail(path, "binvox files cannot be written yet"); }

}  // namespace corrlap::io_detail

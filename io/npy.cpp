// numpy volumes (io/detail/volume_readers.hpp). Not written yet: every call is a named error.
#include <corrlap/io/detail/volume_readers.hpp>

namespace corrlap::io_detail {

void read_npy(const std::string& path, VoxelSink&) { fail(path, "numpy files cannot be read yet"); }
void write_npy(const std::string& path, const VolumeData&) { fail(path, "numpy files cannot be written yet"); }

}  // namespace corrlap::io_detail

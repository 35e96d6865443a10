// MetaImage volumes (io/detail/volume_readers.hpp). Not written yet: every call is a named error.
#include <corrlap/io/detail/volume_readers.hpp>

namespace corrlap::io_detail {

void read_metaimage(const std::string& path, VoxelSink&) { fail(path, "MetaImage files cannot be read yet"); }
void write_metaimage(const std::string& path, const VolumeData&) {
  fail(path, "MetaImage files cannot be written yet");
}

}  // namespace corrlap::io_detail

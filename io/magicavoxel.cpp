// MagicaVoxel volumes (io/detail/volume_readers.hpp).
// The .vox format: "VOX " and a 4-byte version, then chunks: a 4-byte id, the byte counts of its
// content and of its children (little-endian int32), the content, the children. The MAIN chunk's
// children hold the model: SIZE (x, y, z voxels, each at most 256) then XYZI (a count, then one
// (x, y, z, colour index) byte quadruple per set voxel), and other chunks (palette, materials,
// scene graph) that are skipped. The values are the colour indices 1..255, 0 is empty; MagicaVoxel's
// z axis is up and is kept as the volume's k axis.
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <fstream>
#include <vector>

namespace corrlap::io_detail {

namespace {

constexpr int kMaxSide = 256;  // MagicaVoxel's own limit; the coordinates are bytes

std::uint32_t le32(const unsigned char* b) {
  return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
}

struct Chunk {
  std::string id;
  std::uint64_t content = 0, children = 0;
};

}  // namespace

void read_magicavoxel(const std::string& path, VoxelSink& sink) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  const std::uint64_t file_bytes = bytes_left(in);
  auto read_exactly = [&](unsigned char* out, std::size_t n, const std::string& what) {
    in.read(reinterpret_cast<char*>(out), std::streamsize(n));
    if (std::size_t(in.gcount()) != n) fail(path, "truncated MagicaVoxel file in " + what);
  };
  unsigned char start[8];
  in.read(reinterpret_cast<char*>(start), 8);
  if (in.gcount() < 4 || std::string(reinterpret_cast<char*>(start), 4) != "VOX ")
    fail(path, "not a MagicaVoxel file (missing the 'VOX ' magic)");
  if (in.gcount() != 8) fail(path, "truncated MagicaVoxel file in the version");
  const std::uint32_t version = le32(start + 4);
  if (version != 150 && version != 200)
    fail(path, "unsupported MagicaVoxel version " + std::to_string(version) + " (supported: 150, 200)");
  auto chunk_header = [&](const std::string& where) {
    unsigned char b[12];
    read_exactly(b, 12, where);
    Chunk c;
    c.id.assign(reinterpret_cast<char*>(b), 4);
    c.content = le32(b + 4);
    c.children = le32(b + 8);
    return c;
  };
  const Chunk main = chunk_header("the MAIN chunk");
  if (main.id != "MAIN") fail(path, "the first MagicaVoxel chunk is '" + main.id + "', not MAIN");
  if (main.content != 0 || 20 + main.children != file_bytes)
    fail(path, "MagicaVoxel MAIN chunk announces " + readable_count(main.content + main.children) +
                   " bytes, the file holds " + readable_count(file_bytes - std::min<std::uint64_t>(file_bytes, 20)) +
                   " after its header");
  VolumeHeader header;
  std::vector<std::uint8_t> dense;
  int models = 0;
  bool have_voxels = false;
  std::uint64_t left = main.children;
  while (left > 0) {
    if (left < 12) fail(path, "MagicaVoxel chunk header cut by the end of the MAIN chunk");
    const Chunk c = chunk_header("a chunk header");
    left -= 12;
    if (c.content > left || c.children > left - c.content)
      fail(path, "MagicaVoxel chunk '" + c.id + "' announces " + readable_count(c.content + c.children) +
                     " bytes, more than the " + readable_count(left) + " left in the file");
    left -= c.content + c.children;
    if (c.id == "SIZE") {
      if (++models > 1)
        fail(path,
             "the file holds several models (SIZE chunks); corrlap reads single-model files (export one "
             "model from MagicaVoxel)");
      if (c.content != 12)
        fail(path, "MagicaVoxel SIZE chunk of " + readable_count(c.content) + " bytes (expected 12)");
      unsigned char b[12];
      read_exactly(b, 12, "the SIZE chunk");
      for (int a = 0; a < 3; ++a) {
        const std::uint32_t v = le32(b + 4 * a);
        if (v < 1 || v > std::uint32_t(kMaxSide))
          fail(path, "MagicaVoxel SIZE " + std::to_string(le32(b)) + " x " + std::to_string(le32(b + 4)) + " x " +
                         std::to_string(le32(b + 8)) + ": each side must be 1 to 256 voxels");
        header.size[a] = int(v);
      }
      // At most 256^3 bytes, and checked against the budget before they are allocated.
      sink.check(path, header);
      dense.assign(checked_voxels(path, header.size), 0);
      in.seekg(std::streamoff(c.children), std::ios::cur);
    } else if (c.id == "XYZI") {
      if (dense.empty()) fail(path, "MagicaVoxel XYZI chunk before any SIZE chunk");
      if (have_voxels) fail(path, "MagicaVoxel model with two XYZI chunks");
      have_voxels = true;
      unsigned char b[4];
      if (c.content < 4) fail(path, "MagicaVoxel XYZI chunk of " + readable_count(c.content) + " bytes (no count)");
      read_exactly(b, 4, "the XYZI count");
      const std::uint64_t count = le32(b);
      if (4 + 4 * count != c.content)
        fail(path, "MagicaVoxel XYZI chunk of " + readable_count(c.content) + " bytes cannot hold the " +
                       readable_count(count) + " voxels it announces (4 bytes each)");
      std::vector<unsigned char> quads(4 * 4096);
      for (std::uint64_t done = 0; done < count;) {
        const std::size_t k = std::size_t(std::min<std::uint64_t>(4096, count - done));
        read_exactly(quads.data(), 4 * k, "the XYZI voxels");
        for (std::size_t q = 0; q < k; ++q) {
          const unsigned char* v = quads.data() + 4 * q;
          if (v[0] >= header.size.x() || v[1] >= header.size.y() || v[2] >= header.size.z())
            fail(path, "MagicaVoxel voxel " + readable_count(done + q) + " at (" + std::to_string(v[0]) + ", " +
                           std::to_string(v[1]) + ", " + std::to_string(v[2]) + ") is outside the SIZE " +
                           std::to_string(header.size.x()) + " x " + std::to_string(header.size.y()) + " x " +
                           std::to_string(header.size.z()));
          if (v[3] == 0)
            fail(path, "MagicaVoxel voxel " + readable_count(done + q) + " has colour index 0 (1..255; 0 is empty)");
          dense[(std::size_t(v[2]) * std::size_t(header.size.y()) + v[1]) * std::size_t(header.size.x()) + v[0]] = v[3];
        }
        done += k;
      }
      in.seekg(std::streamoff(c.children), std::ios::cur);
    } else {
      // Palette, materials, layers, scene graph: not voxels.
      in.seekg(std::streamoff(c.content + c.children), std::ios::cur);
    }
  }
  if (models == 0) fail(path, "MagicaVoxel file without a SIZE chunk (no model)");
  if (!have_voxels) fail(path, "MagicaVoxel model without an XYZI chunk (no voxels)");
  sink.begin(path, header);
  for (std::size_t done = 0; done < dense.size(); done += kChunk)
    sink.consume(dense.data() + done, std::min(kChunk, dense.size() - done));
}

}  // namespace corrlap::io_detail

#include "volume_stream.hpp"

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

#ifdef CORRLAP_HAVE_ZLIB
#include <zlib.h>
#endif

namespace corrlap::io_detail {

namespace {

// Deflate cannot expand one compressed byte into more than 1032 bytes (a 258-byte match costs at
// least two bits); the constant covers the gzip header and a final partial block.
constexpr std::uint64_t kMaxDeflateRatio = 1032;

// Voxel count in 64 bits, or nullopt when it does not even fit there.
std::optional<std::uint64_t> voxel_count(const Eigen::Vector3i& s) {
  if ((s.array() <= 0).any()) return std::nullopt;
  const auto xy = checked_mul(std::uint64_t(s.x()), std::uint64_t(s.y()));
  return xy ? checked_mul(*xy, std::uint64_t(s.z())) : std::nullopt;
}

// Bytes of the header's values (checked_voxels bounds the count, so this cannot overflow).
std::size_t payload_bytes(const std::string& path, const VolumeHeader& h) {
  return checked_voxels(path, h.size) * value_bytes(h.type);
}

#ifdef CORRLAP_HAVE_ZLIB
// Inflates exactly n bytes into the sink, 1 MiB at a time: the announced size alone never allocates
// memory, and producing more than n bytes is an error as soon as it happens.
void inflate_payload(const std::string& path, const std::string& compressed, std::size_t n, VoxelSink& sink,
                     const std::string& format) {
  // RAII so that every fail() below releases zlib's state.
  struct Stream {
    z_stream zs{};
    bool live = false;
    ~Stream() {
      if (live) inflateEnd(&zs);
    }
  } s;
  // 15 + 32: accept gzip and zlib headers (NRRD "gzip" files are gzip streams, .vol Version 3 zlib).
  if (inflateInit2(&s.zs, 15 + 32) != Z_OK) fail(path, "zlib initialisation failed");
  s.live = true;
  constexpr std::size_t kMaxIn = std::numeric_limits<uInt>::max();
  // One byte of room beyond n detects a stream longer than the sizes announce.
  std::vector<std::uint8_t> buffer(std::min(kChunk, n + 1));
  std::size_t fed = 0, produced = 0;
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    if (s.zs.avail_in == 0 && fed < compressed.size()) {
      const std::size_t k = std::min(compressed.size() - fed, kMaxIn);
      s.zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data() + fed));
      s.zs.avail_in = uInt(k);
      fed += k;
    }
    const std::size_t room = std::min(buffer.size(), n + 1 - produced);
    s.zs.next_out = buffer.data();
    s.zs.avail_out = uInt(room);
    rc = inflate(&s.zs, Z_NO_FLUSH);
    const std::size_t got = room - s.zs.avail_out;
    if (produced + got > n)
      fail(path, format + " data holds more bytes than the sizes announce (" + readable_count(n) + ")");
    if (got > 0) sink.consume(buffer.data(), got);
    produced += got;
    if (rc == Z_BUF_ERROR && s.zs.avail_in == 0 && fed == compressed.size()) break;  // input exhausted
    if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR)
      fail(path, "corrupt " + format + " data" + (s.zs.msg ? std::string(": ") + s.zs.msg : std::string()));
  }
  if (produced != n)
    fail(path,
         "truncated " + format + " data: expected " + readable_count(n) + " bytes, got " + readable_count(produced));
}
#endif

}  // namespace

void fail(const std::string& path, const std::string& what, const std::string& parameter) {
  throw IoError("volume file '" + path + "': " + what, parameter);
}

std::string describe_sizes(const Eigen::Vector3i& s) {
  std::ostringstream os;
  os << "sizes " << s.x() << " x " << s.y() << " x " << s.z();
  if (const auto n = voxel_count(s)) os << " = " << readable_count(*n) << " voxels";
  return os.str();
}

std::size_t checked_voxels(const std::string& path, const Eigen::Vector3i& s) {
  if ((s.array() <= 0).any()) fail(path, describe_sizes(s) + ": dimensions must be positive");
  const auto n = voxel_count(s);
  if (!n || *n > kMaxVoxels)
    fail(path, describe_sizes(s) + (n ? " need " + readable_bytes(double(*n)) : std::string(" overflow 64 bits")) +
                   ", more than the " + readable_bytes(double(kMaxVoxels)) +
                   " a volume may hold (dimensions are absurdly large)");
  return std::size_t(*n);
}

void check_holds(const std::string& path, const Eigen::Vector3i& s, std::uint64_t needed, std::uint64_t available,
                 const std::string& what) {
  if (needed <= available) return;
  fail(path, "truncated data: " + describe_sizes(s) + " need " + what + readable_bytes(double(needed)) +
                 ", more than the " + readable_bytes(double(available)) + " the file holds");
}

void read_payload(std::istream& in, const std::string& path, const VolumeHeader& header, VoxelSink& sink) {
  const std::size_t n = payload_bytes(path, header);
  // Checked before the sink allocates, so that a corrupt header cannot make us allocate gigabytes.
  sink.check(path, header);
  check_holds(path, header.size, n, bytes_left(in));
  sink.begin(path, header);
  std::vector<std::uint8_t> buffer(std::min(n, kChunk));
  std::size_t done = 0;
  while (done < n) {
    const std::size_t k = std::min(kChunk, n - done);
    in.read(reinterpret_cast<char*>(buffer.data()), std::streamsize(k));
    const std::size_t got = std::size_t(in.gcount());
    if (got != k)
      fail(path, "truncated data: expected " + readable_count(n) + " bytes, got " + readable_count(done + got));
    sink.consume(buffer.data(), k);
    done += k;
  }
}

void read_compressed_payload(std::istream& in, const std::string& path, const VolumeHeader& header, VoxelSink& sink,
                             const std::string& format) {
  const std::size_t n = payload_bytes(path, header);
#ifdef CORRLAP_HAVE_ZLIB
  sink.check(path, header);
  const std::uint64_t compressed = bytes_left(in);
  const auto most = checked_mul(compressed, kMaxDeflateRatio);
  if (most && n > *most + 1024)
    fail(path, describe_sizes(header.size) + " need " + readable_bytes(double(n)) + ", more than the " +
                   readable_bytes(double(*most + 1024)) + " that " + readable_bytes(double(compressed)) + " of " +
                   format + " data can hold (deflate expands at most " + std::to_string(kMaxDeflateRatio) + " times)");
  std::ostringstream ss;
  ss << in.rdbuf();  // the compressed bytes only: a few MB for a 1024^3 segmentation
  sink.begin(path, header);
  inflate_payload(path, ss.str(), n, sink, format);
#else
  (void)in;
  (void)n;
  (void)sink;
  fail(path, format + "-compressed data needs corrlap built with zlib (zlib1g-dev)");
#endif
}

bool have_zlib() {
#ifdef CORRLAP_HAVE_ZLIB
  return true;
#else
  return false;
#endif
}

}  // namespace corrlap::io_detail

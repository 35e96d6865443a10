#include "volume_io.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#ifdef CORRLAP_HAVE_ZLIB
#include <zlib.h>
#endif

namespace corrlap {

namespace {

// Hard limit for one volume, whatever the memory budget: 2^34 voxels (16 GiB) is beyond any volume this
// tool is meant for.
// Sizes are checked against it, and against what the file can hold, before anything is allocated.
constexpr std::uint64_t kMaxVoxels = std::uint64_t{1} << 34;
// Deflate cannot expand one compressed byte into more than 1032 bytes (a 258-byte match costs at
// least two bits); the constant covers the gzip header and a final partial block.
constexpr std::uint64_t kMaxDeflateRatio = 1032;

/// `parameter`: the library name of the read option at fault, if one is (InputError::parameter()).
[[noreturn]] void fail(const std::string& path, const std::string& what, const std::string& parameter = {}) {
  throw IoError("volume file '" + path + "': " + what, parameter);
}

// Voxel count in 64 bits, or nullopt when it does not even fit there.
std::optional<std::uint64_t> voxel_count(const Eigen::Vector3i& s) {
  if ((s.array() <= 0).any()) return std::nullopt;
  const auto xy = io_detail::checked_mul(std::uint64_t(s.x()), std::uint64_t(s.y()));
  return xy ? io_detail::checked_mul(*xy, std::uint64_t(s.z())) : std::nullopt;
}

// "sizes 65536 x 65537 x 1 = 4 294 967 296 voxels"
std::string describe(const Eigen::Vector3i& s) {
  std::ostringstream os;
  os << "sizes " << s.x() << " x " << s.y() << " x " << s.z();
  if (const auto n = voxel_count(s)) os << " = " << io_detail::readable_count(*n) << " voxels";
  return os.str();
}

// Positive sizes below the hard limit; returns the voxel count (= bytes of uint8 data). The memory
// budget is checked by the sink, which knows what it will hold (bytes or bits).
std::size_t checked_voxels(const std::string& path, const Eigen::Vector3i& s) {
  if ((s.array() <= 0).any()) fail(path, describe(s) + ": dimensions must be positive");
  const auto n = voxel_count(s);
  if (!n || *n > kMaxVoxels)
    fail(path, describe(s) + (n ? " need " + io_detail::readable_bytes(double(*n)) : std::string(" overflow 64 bits")) +
                   ", more than the " + io_detail::readable_bytes(double(kMaxVoxels)) +
                   " a volume may hold (dimensions are absurdly large)");
  return std::size_t(*n);
}

// Where the readers put the voxel values: begin() once the header gave the sizes, then consume()
// with the values in file order (x fastest), in chunks of any length. A sink that holds the bytes
// (read_volume) or one that thresholds them into bits as they come (read_volume_as_voxels: a 1024^3
// volume is 1 GiB as bytes, 128 MiB as bits).
class VoxelSink {
 public:
  virtual ~VoxelSink() = default;
  /// The memory budget for what the sink will hold (IoError naming the file), before the reader
  /// checks that the file holds the data and before begin() allocates.
  virtual void check(const std::string& path, const Eigen::Vector3i& size) const = 0;
  virtual void begin(const std::string& path, const Eigen::Vector3i& size) = 0;
  virtual void consume(const std::uint8_t* values, std::size_t n) = 0;
};

// Chunk of the streamed reads: large enough for fast reads, small enough to be nothing in memory.
constexpr std::size_t kChunk = std::size_t{1} << 20;

// The announced sizes need `needed` bytes of the file, which holds `available` after the header.
void check_holds(const std::string& path, const Eigen::Vector3i& s, std::uint64_t needed, std::uint64_t available,
                 const std::string& what) {
  if (needed <= available) return;
  fail(path, "truncated data: " + describe(s) + " need " + what + io_detail::readable_bytes(double(needed)) +
                 ", more than the " + io_detail::readable_bytes(double(available)) + " the file holds");
}

// `bytes_per_voxel` bytes for each voxel (8: .longvol), given to the sink as they are.
void read_payload(std::istream& in, const std::string& path, const Eigen::Vector3i& s, VoxelSink& sink,
                  std::size_t bytes_per_voxel = 1) {
  const std::size_t n = checked_voxels(path, s) * bytes_per_voxel;
  // Checked before the sink allocates, so that a corrupt header cannot make us allocate gigabytes.
  sink.check(path, s);
  check_holds(path, s, n, io_detail::bytes_left(in), "");
  sink.begin(path, s);
  std::vector<std::uint8_t> buffer(std::min(n, kChunk));
  std::size_t done = 0;
  while (done < n) {
    const std::size_t k = std::min(kChunk, n - done);
    in.read(reinterpret_cast<char*>(buffer.data()), std::streamsize(k));
    const std::size_t got = std::size_t(in.gcount());
    if (got != k)
      fail(path, "truncated data: expected " + io_detail::readable_count(n) + " bytes, got " +
                     io_detail::readable_count(done + got));
    sink.consume(buffer.data(), k);
    done += k;
  }
}

#ifdef CORRLAP_HAVE_ZLIB
// Inflates exactly n bytes into the sink, 1 MiB at a time: the announced size alone never allocates
// memory, and producing more than n bytes is an error as soon as it happens.
// `format` names the data in messages ("gzip", "zlib").
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
      fail(path, format + " data holds more bytes than the sizes announce (" + io_detail::readable_count(n) + ")");
    if (got > 0) sink.consume(buffer.data(), got);
    produced += got;
    if (rc == Z_BUF_ERROR && s.zs.avail_in == 0 && fed == compressed.size()) break;  // input exhausted
    if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR)
      fail(path, "corrupt " + format + " data" + (s.zs.msg ? std::string(": ") + s.zs.msg : std::string()));
  }
  if (produced != n)
    fail(path, "truncated " + format + " data: expected " + io_detail::readable_count(n) + " bytes, got " +
                   io_detail::readable_count(produced));
}
#endif

// The rest of `in` as compressed voxel data: refused before inflating when even the densest deflate
// stream of that length could not hold n bytes.
void read_compressed_payload(std::istream& in, const std::string& path, const Eigen::Vector3i& s, std::size_t n,
                             VoxelSink& sink, const std::string& format) {
#ifdef CORRLAP_HAVE_ZLIB
  sink.check(path, s);
  const std::uint64_t compressed = io_detail::bytes_left(in);
  const auto most = io_detail::checked_mul(compressed, kMaxDeflateRatio);
  if (most && n > *most + 1024)
    fail(path, describe(s) + " need " + io_detail::readable_bytes(double(n)) + ", more than the " +
                   io_detail::readable_bytes(double(*most + 1024)) + " that " +
                   io_detail::readable_bytes(double(compressed)) + " of " + format +
                   " data can hold (deflate expands at most " + std::to_string(kMaxDeflateRatio) + " times)");
  std::ostringstream ss;
  ss << in.rdbuf();  // the compressed bytes only: a few MB for a 1024^3 segmentation
  sink.begin(path, s);
  inflate_payload(path, ss.str(), n, sink, format);
#else
  (void)in;
  (void)s;
  (void)n;
  (void)sink;
  fail(path, format + "-compressed data needs corrlap built with zlib (zlib1g-dev)");
#endif
}

// DGtal .longvol voxels are 64-bit little-endian words: this sink assembles them and gives the
// next sink one byte per voxel, `to_byte(word)` (which may refuse a value, naming it).
class WordSink final : public VoxelSink {
 public:
  using ToByte = std::function<std::uint8_t(std::uint64_t)>;
  WordSink(VoxelSink& next, ToByte to_byte) : next_(next), to_byte_(std::move(to_byte)) {}
  void check(const std::string& path, const Eigen::Vector3i& size) const override { next_.check(path, size); }
  void begin(const std::string& path, const Eigen::Vector3i& size) override { next_.begin(path, size); }
  void consume(const std::uint8_t* bytes, std::size_t n) override {
    for (std::size_t i = 0; i < n; ++i) {
      word_ |= std::uint64_t(bytes[i]) << (8 * filled_);
      if (++filled_ < 8) continue;
      out_.push_back(to_byte_(word_));
      word_ = 0, filled_ = 0;
      if (out_.size() == kChunk) flush();
    }
    flush();  // a chunk may end inside a word: its bytes wait in word_ for the next chunk
  }

 private:
  void flush() {
    if (!out_.empty()) next_.consume(out_.data(), out_.size());
    out_.clear();
  }
  VoxelSink& next_;
  ToByte to_byte_;
  std::vector<std::uint8_t> out_;
  std::uint64_t word_ = 0;
  unsigned filled_ = 0;
};

// DGtal .vol: "Key: value" lines ended by a line "."; then X*Y*Z bytes, x fastest: raw
// (Version 2, or no Version field) or one zlib stream (Version 3, DGtal's VolWriter with compression).
// .longvol: the same header (Lvoxel-* fields for Voxel-*), 8 bytes per voxel, little-endian; the
// words go through a WordSink made by the caller.
void read_vol(const std::string& path, VoxelSink& sink, std::size_t bytes_per_voxel = 1) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  std::map<std::string, std::string> fields;
  std::string line;
  int lines = 0;
  bool ended = false;
  while (std::getline(in, line)) {
    if (++lines > 256) fail(path, "header too long (missing '.' line?)");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == ".") {
      ended = true;
      break;
    }
    const auto colon = line.find(':');
    if (colon == std::string::npos) fail(path, "malformed header line '" + line.substr(0, 60) + "'");
    std::string key = line.substr(0, colon), value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    fields[key] = value;
  }
  if (!ended) fail(path, "header not terminated by a '.' line");
  Eigen::Vector3i s;
  const char* keys[3] = {"X", "Y", "Z"};
  for (int a = 0; a < 3; ++a) {
    auto it = fields.find(keys[a]);
    if (it == fields.end()) fail(path, std::string("header has no '") + keys[a] + "' field");
    char* end = nullptr;
    const long d = std::strtol(it->second.c_str(), &end, 10);
    if (*end != '\0' || d <= 0 || d > 1000000)
      fail(path, std::string("invalid dimension ") + keys[a] + ": '" + it->second + "'");
    s[a] = int(d);
  }
  const std::size_t n = checked_voxels(path, s);
  const auto version = fields.find("Version");
  const std::string ver = version == fields.end() ? "2" : version->second;
  if (ver == "2")
    read_payload(in, path, s, sink, bytes_per_voxel);
  else if (ver == "3")
    read_compressed_payload(in, path, s, n * bytes_per_voxel, sink, "zlib");
  else
    fail(path, "unsupported Version '" + ver.substr(0, 20) + "' (supported: 2 raw, 3 zlib)");
}

// The voxel values, then commit: a failed write leaves no half-written volume (io/detail/output_file.hpp).
void write_values(io_detail::OutputFile& out, const Volume& v) {
  // A short write sets the stream's error flag, which commit() reports naming the file.
  if (!v.values.empty()) (void)std::fwrite(v.values.data(), 1, v.values.size(), out.get());
  out.commit();
}

// The payload of a .vol (the bytes) or .longvol (each byte as a 64-bit little-endian word), in
// chunks of at most kChunk voxels: emit(data, length, last).
template <class Emit>
void for_each_payload_chunk(const Volume& v, bool longvol, Emit&& emit) {
  std::vector<std::uint8_t> words;
  std::size_t fed = 0;
  do {
    const std::size_t k = std::min(kChunk, v.values.size() - fed);
    const std::uint8_t* data = v.values.data() + fed;
    if (longvol) {
      words.assign(8 * k, 0);
      for (std::size_t i = 0; i < k; ++i) words[8 * i] = data[i];  // little-endian: the low byte first
      data = words.data();
    }
    fed += k;
    emit(data, longvol ? 8 * k : k, fed == v.values.size());
  } while (fed < v.values.size());
}

void write_vol(const std::string& path, const Volume& v, bool compressed, bool longvol) {
#ifndef CORRLAP_HAVE_ZLIB
  if (compressed) fail(path, "Version 3 (zlib) needs corrlap built with zlib (zlib1g-dev)");
#endif
  io_detail::OutputFile out(path, "volume", true);
  // DGtal's VolWriter and LongvolWriter headers (LongvolWriter writes "Lvoxel-Size: 4").
  std::fprintf(out.get(), "Center-X: %d\nCenter-Y: %d\nCenter-Z: %d\nX: %d\nY: %d\nZ: %d\n%s\nAlpha-Color: 0\n%s\n",
               v.size.x() / 2, v.size.y() / 2, v.size.z() / 2, v.size.x(), v.size.y(), v.size.z(),
               longvol ? "Lvoxel-Size: 4" : "Voxel-Size: 1", longvol ? "Lvoxel-Endian: 0" : "Voxel-Endian: 0");
  std::fprintf(out.get(), "Int-Endian: 0123\nVersion: %d\n.\n", compressed ? 3 : 2);
  if (!compressed) {
    if (!longvol) return write_values(out, v);
    // A short write sets the stream's error flag, which commit() reports naming the file.
    for_each_payload_chunk(
        v, true, [&](const std::uint8_t* data, std::size_t n, bool) { (void)std::fwrite(data, 1, n, out.get()); });
    return out.commit();
  }
#ifdef CORRLAP_HAVE_ZLIB
  // One zlib stream, deflated 1 MiB of voxels at a time: the compressed volume is never held whole.
  struct Stream {
    z_stream zs{};
    bool live = false;
    ~Stream() {
      if (live) deflateEnd(&zs);
    }
  } s;
  if (deflateInit(&s.zs, Z_DEFAULT_COMPRESSION) != Z_OK) fail(path, "zlib initialisation failed");
  s.live = true;
  std::vector<unsigned char> buffer(kChunk);
  for_each_payload_chunk(v, longvol, [&](const std::uint8_t* data, std::size_t n, bool last) {
    s.zs.next_in = const_cast<Bytef*>(data);
    s.zs.avail_in = uInt(n);
    const int flush = last ? Z_FINISH : Z_NO_FLUSH;
    int rc = Z_OK;
    do {
      s.zs.next_out = buffer.data();
      s.zs.avail_out = uInt(buffer.size());
      rc = deflate(&s.zs, flush);
      if (rc == Z_STREAM_ERROR) fail(path, "zlib compression failed");
      (void)std::fwrite(buffer.data(), 1, buffer.size() - s.zs.avail_out, out.get());
    } while (s.zs.avail_out == 0 || (last && rc != Z_STREAM_END));
  });
  out.commit();
#endif
}

void read_raw(const std::string& path, const VolumeReadOptions& options, VoxelSink& sink) {
  if (!options.raw_dimensions)
    fail(path, "raw volumes need their dimensions (raw_dimensions: NX NY NZ)", "raw_dimensions");
  checked_voxels(path, *options.raw_dimensions);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  // Checked before reading: the file must be exactly the given dimensions.
  const std::uint64_t n = *voxel_count(*options.raw_dimensions), bytes = io_detail::bytes_left(in);
  if (bytes > n) fail(path, "file is larger than the given dimensions");
  read_payload(in, path, *options.raw_dimensions, sink);
}

void write_raw(const std::string& path, const Volume& v) {
  io_detail::OutputFile out(path, "volume", true);
  write_values(out, v);
}

// ---- NRRD (http://teem.sourceforge.net/nrrd/format.html) ----
// Attached header "NRRD000N", "field: value" lines, a blank line, then the data. We read 3D uint8
// volumes (type uint8/uchar/unsigned char/uint8_t, or int8 kept only if non-negative) with raw,
// ascii/text or gzip encoding (gzip when built with zlib); anything else is a clear error.
std::string trim(std::string s) {
  s.erase(0, s.find_first_not_of(" \t"));
  const auto e = s.find_last_not_of(" \t\r");
  s.erase(e == std::string::npos ? 0 : e + 1);
  return s;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// Forwards to another sink after checking that int8 data holds no negative values.
class NonNegativeInt8 final : public VoxelSink {
 public:
  explicit NonNegativeInt8(VoxelSink& next) : next_(next) {}
  void check(const std::string& path, const Eigen::Vector3i& size) const override { next_.check(path, size); }
  void begin(const std::string& path, const Eigen::Vector3i& size) override {
    path_ = path;
    next_.begin(path, size);
  }
  void consume(const std::uint8_t* values, std::size_t n) override {
    for (std::size_t i = 0; i < n; ++i)
      if (values[i] > 127) fail(path_, "negative int8 values are not supported (grey levels must be 0..127 for int8)");
    next_.consume(values, n);
  }

 private:
  VoxelSink& next_;
  std::string path_;
};

void read_nrrd(const std::string& path, VoxelSink& destination) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  std::string line;
  if (!std::getline(in, line)) fail(path, "empty file");
  if (line.rfind("NRRD000", 0) != 0) fail(path, "not a NRRD file (missing NRRD000x magic)");
  std::map<std::string, std::string> fields;
  bool ended = false;
  int lines = 0;
  while (std::getline(in, line)) {
    if (++lines > 1024) fail(path, "header too long");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) {
      ended = true;
      break;
    }
    if (line[0] == '#') continue;
    if (line.find(":=") != std::string::npos) continue;  // key/value pairs: free-form metadata
    const auto colon = line.find(": ");
    if (colon == std::string::npos) fail(path, "malformed header line '" + line.substr(0, 60) + "'");
    fields[lower(trim(line.substr(0, colon)))] = trim(line.substr(colon + 2));
  }
  auto field = [&](const char* key) -> std::string {
    auto it = fields.find(key);
    if (it == fields.end()) fail(path, std::string("header has no '") + key + "' field");
    return it->second;
  };
  if (fields.count("data file") || fields.count("datafile"))
    fail(path, "detached data ('data file' field) is not supported; use an attached-header .nrrd");
  const std::string type = lower(field("type"));
  const bool u8 = type == "uint8" || type == "uchar" || type == "unsigned char" || type == "uint8_t";
  const bool s8 = type == "int8" || type == "signed char" || type == "int8_t";
  if (!u8 && !s8) fail(path, "unsupported type '" + type + "' (supported: uint8/uchar, int8)");
  const std::string dim = field("dimension");
  if (dim != "3") fail(path, "dimension must be 3, got '" + dim + "'");
  Eigen::Vector3i s;
  {
    std::istringstream ss(field("sizes"));
    long long d[3];
    std::string extra;
    if (!(ss >> d[0] >> d[1] >> d[2]) || (ss >> extra)) fail(path, "malformed 'sizes' field (expected three integers)");
    for (int a = 0; a < 3; ++a) {
      if (d[a] <= 0 || d[a] > 1000000)
        fail(path, "invalid size " + std::to_string(d[a]) + " on axis " + std::to_string(a));
      s[a] = int(d[a]);
    }
  }
  const std::size_t n = checked_voxels(path, s);
  if (auto it = fields.find("endian");
      it != fields.end() && lower(it->second) != "little" && lower(it->second) != "big")
    fail(path, "invalid endian '" + it->second + "' (little or big)");  // irrelevant for 1-byte types
  const std::string encoding = lower(field("encoding"));
  if (!ended) fail(path, "header not terminated by a blank line (truncated file?)");
  NonNegativeInt8 checked(destination);
  VoxelSink& sink = s8 ? static_cast<VoxelSink&>(checked) : destination;
  if (encoding == "raw") {
    if (io_detail::bytes_left(in) > n) fail(path, "file is larger than the announced sizes");
    read_payload(in, path, s, sink);
  } else if (encoding == "ascii" || encoding == "text" || encoding == "txt") {
    // n values need at least n digits and n - 1 separators.
    sink.check(path, s);
    check_holds(path, s, 2 * std::uint64_t(n) - 1, io_detail::bytes_left(in), "at least ");
    sink.begin(path, s);
    std::vector<std::uint8_t> buffer;
    buffer.reserve(std::min(n, kChunk));
    for (std::size_t i = 0; i < n; ++i) {
      long long x = 0;
      if (!(in >> x)) fail(path, "truncated or malformed ascii data at value " + std::to_string(i));
      if (x < (s8 ? -128 : 0) || x > (s8 ? 127 : 255))
        fail(path, "ascii value " + std::to_string(x) + " out of range for " + type);
      buffer.push_back(std::uint8_t(x));
      if (buffer.size() == kChunk || i + 1 == n) {
        sink.consume(buffer.data(), buffer.size());
        buffer.clear();
      }
    }
    std::string extra;
    if (in >> extra) fail(path, "more ascii values than the announced sizes");
  } else if (encoding == "gzip" || encoding == "gz") {
    read_compressed_payload(in, path, s, n, sink, "gzip");
  } else {
    fail(path, "unsupported encoding '" + encoding + "' (supported: raw, ascii, gzip)");
  }
}

// The values as bytes (read_volume).
class VolumeSink final : public VoxelSink {
 public:
  void check(const std::string& path, const Eigen::Vector3i& size) const override {
    io_detail::check_budget("volume file '" + path + "'", double(checked_voxels(path, size)), describe(size));
  }
  void begin(const std::string& path, const Eigen::Vector3i& size) override {
    const std::size_t n = checked_voxels(path, size);
    volume.size = size;
    volume.values.reserve(n);
  }
  void consume(const std::uint8_t* values, std::size_t n) override {
    volume.values.insert(volume.values.end(), values, values + n);
  }
  Volume volume;
};

// The values thresholded into a voxel grid as they arrive, one (y, z) row of 64-bit words at a
// time (read_volume_as_voxels, threshold_volume): the bytes are never held. The box is
// [0, size - 1] - shift padded by one empty voxel on every side; h (0: unit_size_grid_step) and the
// shift (volume_centering_shift when centred) follow from the sizes, known at begin().
class ThresholdSink final : public VoxelSink {
 public:
  ThresholdSink(double threshold, double h, bool centered) : h_(h), centered_(centered) {
    for (int v = 0; v < 256; ++v) inside_[std::size_t(v)] = double(v) > threshold;
  }
  void check(const std::string& path, const Eigen::Vector3i& size) const override {
    // The grid's rows of 64-bit words over the padded box (core/voxel_grid.hpp).
    const double words = std::ceil(double(size.x() + 2) / 64.0) * double(size.y() + 2) * double(size.z() + 2);
    io_detail::check_budget("volume file '" + path + "'", 8.0 * words, describe(size) + " as a bit grid");
  }
  void begin(const std::string&, const Eigen::Vector3i& size) override {
    size_ = size;
    shift_ = centered_ ? volume_centering_shift(size) : Eigen::Vector3i::Zero();
    const double h = h_ == 0.0 ? unit_size_grid_step(size) : h_;
    grid = VoxelGrid(Eigen::Vector3i::Constant(-1) - shift_, size - shift_, h);  // checks the budget
  }
  void consume(const std::uint8_t* values, std::size_t n) override {
    while (n > 0) {
      // Voxel x_ of row (y_, z_) is bit x_ + 1 of the grid row (the box starts one voxel before).
      const std::size_t k = std::min(n, std::size_t(size_.x() - x_));
      std::uint64_t* words = grid.row(y_ - shift_.y(), z_ - shift_.z());
      for (std::size_t i = 0; i < k; ++i) {
        const std::uint64_t bit = inside_[values[i]];
        const std::size_t b = std::size_t(x_) + i + 1;
        words[b >> 6] |= bit << (b & 63);
        inside += bit;
      }
      values += k;
      n -= k;
      x_ += int(k);
      if (x_ == size_.x()) {
        x_ = 0;
        if (++y_ == size_.y()) {
          y_ = 0;
          ++z_;
        }
      }
    }
  }
  VoxelGrid grid;
  std::uint64_t inside = 0;

 private:
  double h_;
  bool centered_;
  Eigen::Vector3i shift_ = Eigen::Vector3i::Zero(), size_ = Eigen::Vector3i::Zero();
  int x_ = 0, y_ = 0, z_ = 0;
  std::array<bool, 256> inside_{};
};

// `word_to_byte`: what a .longvol voxel becomes for the sink.
void read_into(const std::string& path, const VolumeReadOptions& options, VoxelSink& sink,
               const WordSink::ToByte& word_to_byte) {
  const std::string ext = file_extension(path);
  if (ext == "vol") return read_vol(path, sink);
  if (ext == "longvol") {
    WordSink words(sink, word_to_byte);
    return read_vol(path, words, 8);
  }
  if (ext == "raw") return read_raw(path, options, sink);
  if (ext == "nrrd") return read_nrrd(path, sink);
  fail(path, "unsupported extension '" + ext + "' (supported: .vol, .longvol, .raw, .nrrd)");
}

void write_nrrd(const std::string& path, const Volume& v) {
  io_detail::OutputFile out(path, "volume", true);
  std::fprintf(
      out.get(),
      "NRRD0004\n# written by corrlap\ntype: uint8\ndimension: 3\nsizes: %d %d %d\nencoding: raw\nendian: little\n\n",
      v.size.x(), v.size.y(), v.size.z());
  write_values(out, v);
}

}  // namespace

bool nrrd_gzip_supported() {
#ifdef CORRLAP_HAVE_ZLIB
  return true;
#else
  return false;
#endif
}

Volume read_volume(const std::string& path, const VolumeReadOptions& options) {
  VolumeSink sink;
  read_into(path, options, sink, [&path](std::uint64_t word) {
    if (word > 255)
      fail(path,
           "longvol value " + std::to_string(word) +
               " does not fit the uint8 volume; read it thresholded (read_volume_as_voxels with a threshold)",
           "threshold");
    return std::uint8_t(word);
  });
  return std::move(sink.volume);
}

void write_volume(const std::string& path, const Volume& volume, const VolumeWriteOptions& options) {
  const std::string ext = file_extension(path);
  const auto n = voxel_count(volume.size);
  if (!n || volume.values.size() != *n)
    fail(path, "volume data (" + io_detail::readable_count(volume.values.size()) + " values) does not match its " +
                   describe(volume.size));
  if (options.compressed && ext != "vol" && ext != "longvol")
    fail(path, "compressed writing is for .vol and .longvol files (Version 3); ." + ext + " is written uncompressed");
  if (ext == "vol" || ext == "longvol") return write_vol(path, volume, options.compressed, ext == "longvol");
  if (ext == "raw") return write_raw(path, volume);
  if (ext == "nrrd") return write_nrrd(path, volume);
  fail(path, "unsupported extension '" + ext + "' for writing (supported: .vol, .longvol, .raw, .nrrd)");
}

VoxelGrid threshold_volume(const Volume& volume, double threshold, double h) {
  const Eigen::Vector3i s = volume.size;
  // A hand-built Volume whose values do not match its size would be read out of bounds below.
  const auto n = voxel_count(s);
  if (!n || volume.values.size() != *n)
    throw InputError("volume: " + io_detail::readable_count(volume.values.size()) + " values do not match its " +
                     describe(s));
  if (!(h > 0.0)) throw InputError("volume: h must be positive");
  ThresholdSink sink(threshold, h, false);  // the same thresholding as the streamed read
  sink.begin("", s);
  sink.consume(volume.values.data(), volume.values.size());
  if (sink.inside == 0)
    throw InputError("volume: no voxel above the threshold " + io_detail::readable_number(threshold) +
                     " (empty volume)");
  return std::move(sink.grid);
}

double unit_size_grid_step(const Eigen::Vector3i& size) { return size.maxCoeff() > 0 ? 2.0 / size.maxCoeff() : 1.0; }

Eigen::Vector3i volume_centering_shift(const Eigen::Vector3i& size) { return (size - Eigen::Vector3i::Ones()) / 2; }

VoxelGrid read_volume_as_voxels(const std::string& path, const VolumeReadOptions& options) {
  if (options.h < 0.0 || !std::isfinite(options.h))
    throw InputError("volume '" + path + "': h must be positive (or 0: unit size)");
  // A .longvol word is compared with the threshold itself (labels may exceed 255): 1 inside, 0 out.
  const bool words = file_extension(path) == "longvol";
  ThresholdSink sink(words ? 0.5 : options.threshold, options.h, options.centered);
  read_into(path, options, sink,
            [&options](std::uint64_t word) { return std::uint8_t(double(word) > options.threshold); });
  if (sink.inside == 0)
    throw InputError("volume '" + path + "': no voxel above the threshold " +
                     io_detail::readable_number(options.threshold) + " (empty volume)");
  return std::move(sink.grid);
}

Volume voxels_to_volume(const VoxelGrid& grid) {
  Volume v;
  v.size = grid.size();
  v.values.assign(checked_voxels("(voxel grid)", v.size), 0);
  const Eigen::Vector3i lo = grid.lower();
  for (int z = 0; z < v.size.z(); ++z)
    for (int y = 0; y < v.size.y(); ++y)
      for (int x = 0; x < v.size.x(); ++x)
        if (grid.get(x + lo.x(), y + lo.y(), z + lo.z()))
          v.values[(std::size_t(z) * std::size_t(v.size.y()) + std::size_t(y)) * std::size_t(v.size.x()) +
                   std::size_t(x)] = 255;
  return v;
}

}  // namespace corrlap

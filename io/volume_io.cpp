#include "volume_io.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/inside_test.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <corrlap/io/detail/volume_stream.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <type_traits>

#ifdef CORRLAP_HAVE_ZLIB
#include <zlib.h>
#endif

namespace corrlap {

namespace {

using io_detail::check_holds;
using io_detail::checked_voxels;
using io_detail::describe_sizes;
using io_detail::fail;
using io_detail::kChunk;
using io_detail::VolumeHeader;
using io_detail::VoxelSink;

// Voxel count in 64 bits, or nullopt when a size is not positive or the count does not fit.
std::optional<std::uint64_t> voxel_count(const Eigen::Vector3i& s) {
  if ((s.array() <= 0).any()) return std::nullopt;
  const auto xy = io_detail::checked_mul(std::uint64_t(s.x()), std::uint64_t(s.y()));
  return xy ? io_detail::checked_mul(*xy, std::uint64_t(s.z())) : std::nullopt;
}

// DGtal .vol: "Key: value" lines ended by a line "."; then X*Y*Z bytes, x fastest: raw
// (Version 2, or no Version field) or one zlib stream (Version 3, DGtal's VolWriter with compression).
// .longvol: the same header (Lvoxel-* fields for Voxel-*), 8 bytes per voxel, little-endian.
void read_vol(const std::string& path, VoxelSink& sink, bool longvol) {
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
  VolumeHeader header;
  header.size = s;
  header.type = longvol ? VoxelValueType::UInt64 : VoxelValueType::UInt8;
  const auto version = fields.find("Version");
  const std::string ver = version == fields.end() ? "2" : version->second;
  if (ver == "2")
    io_detail::read_payload(in, path, header, sink);
  else if (ver == "3")
    io_detail::read_compressed_payload(in, path, header, sink, "zlib");
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
  VolumeHeader header;
  header.size = *options.raw_dimensions;
  if (io_detail::bytes_left(in) > checked_voxels(path, header.size))
    fail(path, "file is larger than the given dimensions");
  io_detail::read_payload(in, path, header, sink);
}

void write_raw(const std::string& path, const Volume& v) {
  io_detail::OutputFile out(path, "volume", true);
  write_values(out, v);
}

// Hands the values to values() whole: a chunk that ends inside a value keeps its bytes for the next.
class WholeValueSink : public VoxelSink {
 public:
  void begin(const std::string& path, const VolumeHeader& header) override {
    path_ = path;
    header_ = header;
    bytes_ = value_bytes(header.type);
    first_ = 0;
    start(header);
  }
  void consume(const std::uint8_t* bytes, std::size_t n) override {
    if (filled_ > 0) {
      const std::size_t k = std::min(n, bytes_ - filled_);
      std::copy(bytes, bytes + k, carry_.begin() + std::ptrdiff_t(filled_));
      filled_ += k, bytes += k, n -= k;
      if (filled_ < bytes_) return;
      values(carry_.data(), 1);
      ++first_;
      filled_ = 0;
    }
    const std::size_t whole = n / bytes_;
    if (whole > 0) values(bytes, whole);
    first_ += whole;
    filled_ = n - whole * bytes_;
    std::copy(bytes + whole * bytes_, bytes + n, carry_.begin());
  }

 protected:
  /// Once the header is known.
  virtual void start(const VolumeHeader& header) = 0;
  /// `count` whole values in the stream's byte order, the next ones in stream order (the first is
  /// the stream's value number first()).
  virtual void values(const std::uint8_t* bytes, std::size_t count) = 0;
  const std::string& path() const { return path_; }
  const VolumeHeader& header() const { return header_; }
  /// True when the stream is i fastest, then j, then k: value number n is voxel n.
  bool in_index_order() const { return header_.order == std::array<int, 3>{0, 1, 2}; }
  std::uint64_t first() const { return first_; }
  /// The voxel (i, j, k) of the stream's value number n.
  Eigen::Vector3i voxel_of(std::uint64_t n) const {
    Eigen::Vector3i v;
    for (int a : header_.order) {
      const auto m = std::uint64_t(header_.size[a]);
      v[a] = int(n % m);
      n /= m;
    }
    return v;
  }
  /// The position of voxel v in i-fastest order.
  std::size_t linear_index(const Eigen::Vector3i& v) const {
    const Eigen::Vector3i& s = header_.size;
    return (std::size_t(v.z()) * std::size_t(s.y()) + std::size_t(v.y())) * std::size_t(s.x()) + std::size_t(v.x());
  }

 private:
  std::string path_;
  VolumeHeader header_;
  std::size_t bytes_ = 1, filled_ = 0;
  std::uint64_t first_ = 0;
  std::array<std::uint8_t, 8> carry_{};
};

// Calls f(T{}, swapped) with the value type of the header and whether its bytes need reversing.
template <class F>
void visit_stream_type(const VolumeHeader& header, F&& f) {
  const bool swap = header.big_endian != (std::endian::native == std::endian::big) && value_bytes(header.type) > 1;
  io_detail::visit_value_type(header.type, [&](auto t) {
    if (swap)
      f(t, std::true_type{});
    else
      f(t, std::false_type{});
  });
}

// The values as uint8 bytes (read_volume's Volume): other types are converted when every value is
// an integer in 0..255, and refused naming the first that is not.
class VolumeSink final : public WholeValueSink {
 public:
  void check(const std::string& path, const VolumeHeader& header) const override {
    io_detail::check_budget("volume file '" + path + "'", double(checked_voxels(path, header.size)),
                            describe_sizes(header.size));
  }
  Volume volume;

 private:
  void start(const VolumeHeader& header) override {
    volume.size = header.size;
    // Another stream order puts each value at its place; i fastest appends.
    if (in_index_order())
      volume.values.reserve(checked_voxels(path(), header.size));
    else
      volume.values.assign(checked_voxels(path(), header.size), 0);
  }
  void put(std::size_t i, std::uint8_t v) {
    if (in_index_order())
      volume.values.push_back(v);
    else
      volume.values[linear_index(voxel_of(first() + i))] = v;
  }
  void values(const std::uint8_t* bytes, std::size_t count) override {
    if (header().type == VoxelValueType::UInt8 && in_index_order()) {
      volume.values.insert(volume.values.end(), bytes, bytes + count);
      return;
    }
    visit_stream_type(header(), [&](auto t, auto swapped) {
      using T = decltype(t);
      const std::size_t size = value_bytes(header().type);
      for (std::size_t i = 0; i < count; ++i) {
        const T v = io_detail::read_value<T, decltype(swapped)::value>(bytes + i * size);
        if (!(double(v) >= 0.0 && double(v) <= 255.0 && double(v) == std::floor(double(v))))
          fail(path(),
               value_type_name(header().type) + " value " +
                   (std::is_integral_v<T> ? std::to_string(v) : io_detail::readable_number(double(v))) +
                   " does not fit a uint8 volume; read the file thresholded (read_volume_as_voxels) or in its own "
                   "type (read_volume_data)",
               "threshold");
        put(i, std::uint8_t(v));
      }
    });
  }
};

// The values in their own type, in native byte order (read_volume_data).
class VolumeDataSink final : public WholeValueSink {
 public:
  void check(const std::string& path, const VolumeHeader& header) const override {
    io_detail::check_budget("volume file '" + path + "'",
                            double(checked_voxels(path, header.size)) * double(value_bytes(header.type)),
                            describe_sizes(header.size) + " of " + value_type_name(header.type));
  }
  VolumeData data;

 private:
  void start(const VolumeHeader& header) override {
    data.size = header.size;
    data.type = header.type;
    data.geometry = header.geometry;
    // Another stream order puts each value at its place; i fastest appends.
    const std::size_t n = checked_voxels(path(), header.size) * value_bytes(header.type);
    if (in_index_order())
      data.bytes.reserve(n);
    else
      data.bytes.assign(n, 0);
  }
  void values(const std::uint8_t* bytes, std::size_t count) override {
    const std::size_t size = value_bytes(header().type);
    const bool swap = size > 1 && header().big_endian != (std::endian::native == std::endian::big);
    for (std::size_t i = 0; i < count; ++i) {
      std::size_t at = data.bytes.size();
      if (in_index_order()) {
        data.bytes.insert(data.bytes.end(), bytes + i * size, bytes + (i + 1) * size);
      } else {
        at = linear_index(voxel_of(first() + i)) * size;
        std::copy(bytes + i * size, bytes + (i + 1) * size, data.bytes.begin() + std::ptrdiff_t(at));
      }
      if (swap) std::reverse(data.bytes.begin() + std::ptrdiff_t(at), data.bytes.begin() + std::ptrdiff_t(at + size));
    }
  }
};

// The box of read_volume_as_voxels's grid for a volume of `size` voxels: [0, size - 1] - shift
// padded by one empty voxel on every side, shift = volume_centering_shift(size) when centred.
void padded_box(const Eigen::Vector3i& size, bool centered, Eigen::Vector3i& lower, Eigen::Vector3i& upper) {
  const Eigen::Vector3i shift = centered ? volume_centering_shift(size) : Eigen::Vector3i::Zero();
  lower = Eigen::Vector3i::Constant(-1) - shift;
  upper = size - shift;
}

// The x range [x_first, x_last] of that box clipped to it; InputError naming the range when the
// clipped range is empty.
void clip_x_range(const std::string& path, Eigen::Vector3i& lower, Eigen::Vector3i& upper, int x_first, int x_last) {
  if (x_first > upper.x() || x_last < lower.x() || x_first > x_last)
    throw InputError("volume '" + path + "': the slab of x [" + std::to_string(x_first) + ", " +
                     std::to_string(x_last) + "] is outside the voxel box's x range [" + std::to_string(lower.x()) +
                     ", " + std::to_string(upper.x()) + "]");
  lower.x() = std::max(lower.x(), x_first);
  upper.x() = std::min(upper.x(), x_last);
}

// The values made inside or outside by the rule into a voxel grid as they arrive, one (y, z) row of
// 64-bit words at a time (read_volume_as_voxels, threshold_volume): the values are never held. The
// box is padded_box(size); h (0: unit_size_grid_step) and the shift (volume_centering_shift when
// centred) follow from the sizes, known at begin(). With an x range (a slab: the distributed front
// end reads one per MPI rank), the grid's box is that range of x clipped to the box, with all of y
// and z: every value is still read and checked (a NaN anywhere fails on every rank alike), but only
// the slab's bits are kept.
class ThresholdSink final : public WholeValueSink {
 public:
  ThresholdSink(const InsideRule& rule, double h, bool centered) : rule_(rule), h_(h), centered_(centered) {}
  ThresholdSink(const InsideRule& rule, double h, bool centered, int x_first, int x_last)
      : rule_(rule), h_(h), centered_(centered), x_range_{{x_first, x_last}} {}
  void check(const std::string& path, const VolumeHeader& header) const override {
    // The grid's rows of 64-bit words over the (clipped) padded box (core/voxel_grid.hpp).
    Eigen::Vector3i lower, upper;
    box_of(path, header.size, lower, upper);
    const Eigen::Vector3i size = upper - lower + Eigen::Vector3i::Ones();
    const double words = std::ceil(double(size.x()) / 64.0) * double(size.y()) * double(size.z());
    io_detail::check_budget("volume file '" + path + "'", 8.0 * words,
                            describe_sizes(header.size) + (x_range_ ? " as the bit grid of a slab" : " as a bit grid"));
  }
  VoxelGrid grid;
  VolumeGeometry geometry;
  std::uint64_t inside = 0;

 private:
  void box_of(const std::string& path, const Eigen::Vector3i& size, Eigen::Vector3i& lower,
              Eigen::Vector3i& upper) const {
    padded_box(size, centered_, lower, upper);
    if (x_range_) clip_x_range(path, lower, upper, (*x_range_)[0], (*x_range_)[1]);
  }
  void start(const VolumeHeader& header) override {
    size_ = header.size;
    geometry = header.geometry;
    shift_ = centered_ ? volume_centering_shift(size_) : Eigen::Vector3i::Zero();
    const double h = h_ == 0.0 ? unit_size_grid_step(size_) : h_;
    Eigen::Vector3i lower, upper;
    box_of(path(), size_, lower, upper);
    grid = VoxelGrid(lower, upper, h);  // checks the budget
    // File voxel x is bit x - shift.x - lower.x of a grid row when it lies in the grid's x range.
    bit_offset_ = -shift_.x() - lower.x();
    x_lo_ = lower.x() + shift_.x();
    x_hi_ = upper.x() + shift_.x();
    if (header.type == VoxelValueType::UInt8) {
      const io_detail::InsideTest<std::uint8_t> test(rule_);
      for (int v = 0; v < 256; ++v) byte_inside_[std::size_t(v)] = !test.none && test.inside(std::uint8_t(v));
    }
  }
  void values(const std::uint8_t* bytes, std::size_t count) override {
    if (header().type == VoxelValueType::UInt8)
      return set_bits(count, [&](std::size_t i, int) { return byte_inside_[bytes[i]]; });
    visit_stream_type(header(), [&](auto t, auto swapped) {
      using T = decltype(t);
      const io_detail::InsideTest<T> test(rule_);
      const std::size_t size = value_bytes(header().type);
      set_bits(count, [&](std::size_t i, int x) {
        const T v = io_detail::read_value<T, decltype(swapped)::value>(bytes + i * size);
        if (io_detail::InsideTest<T>::is_nan(v))
          fail(path(), "value at voxel [" + std::to_string(x) + ", " + std::to_string(y_) + ", " + std::to_string(z_) +
                           "] is NaN");
        return !test.none && test.inside(v);
      });
    });
  }
  // is_inside(i, x) for the next `count` voxels, i = 0 .. count - 1; x: its index along the row.
  template <class Inside>
  void set_bits(std::size_t count, Inside&& is_inside) {
    if (!in_index_order()) {
      for (std::size_t i = 0; i < count; ++i) {
        const Eigen::Vector3i v = voxel_of(first() + i);
        x_ = v.x(), y_ = v.y(), z_ = v.z();  // for messages
        if (!is_inside(i, v.x()) || v.x() < x_lo_ || v.x() > x_hi_) continue;
        const int b = v.x() + bit_offset_;
        grid.row(v.y() - shift_.y(), v.z() - shift_.z())[b >> 6] |= std::uint64_t{1} << (b & 63);
        ++inside;
      }
      return;
    }
    std::size_t i = 0;
    while (i < count) {
      // Voxel x_ of row (y_, z_) is bit x_ + bit_offset_ of the grid row; every value is decided
      // (NaN is refused anywhere), the bits outside the grid's x range are dropped.
      const std::size_t k = std::min(count - i, std::size_t(size_.x() - x_));
      std::uint64_t* words = grid.row(y_ - shift_.y(), z_ - shift_.z());
      for (std::size_t j = 0; j < k; ++j) {
        const int x = x_ + int(j);
        const bool in = is_inside(i + j, x);
        if (x < x_lo_ || x > x_hi_) continue;
        const std::uint64_t bit = in ? 1 : 0;
        const std::size_t b = std::size_t(x + bit_offset_);
        words[b >> 6] |= bit << (b & 63);
        inside += bit;
      }
      i += k;
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
  InsideRule rule_;
  double h_;
  bool centered_;
  std::optional<std::array<int, 2>> x_range_;  // digital x, as given
  int bit_offset_ = 1, x_lo_ = 0, x_hi_ = -1;  // file x range kept in the grid
  Eigen::Vector3i shift_ = Eigen::Vector3i::Zero(), size_ = Eigen::Vector3i::Zero();
  int x_ = 0, y_ = 0, z_ = 0;
  std::array<bool, 256> byte_inside_{};
};

// The format of a file by its extension (".nii.gz" counts as one), or a folder of TIFF slices.
std::string volume_format(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return "tiff";
  std::string ext = file_extension(path);
  if (ext == "gz" && file_extension(path.substr(0, path.size() - 3)) == "nii") return "nii";
  if (ext == "tif") return "tiff";
  if (ext == "mhd") return "mha";
  if (ext == "nhdr") return "nrrd";
  return ext;
}

constexpr const char* kReadable =
    "supported: .vol, .longvol, .raw, .nrrd/.nhdr, .nii/.nii.gz, .mha/.mhd, .binvox, .vox, .npy, .tif/.tiff or a "
    "folder "
    "of .tif slices";

void read_into(const std::string& path, const VolumeReadOptions& options, VoxelSink& sink) {
  const std::string format = volume_format(path);
  if (format == "vol") return read_vol(path, sink, false);
  if (format == "longvol") return read_vol(path, sink, true);
  if (format == "raw") return read_raw(path, options, sink);
  if (format == "nrrd") return io_detail::read_nrrd(path, sink);
  if (format == "nii") return io_detail::read_nifti(path, sink);
  if (format == "mha") return io_detail::read_metaimage(path, sink);
  if (format == "binvox") return io_detail::read_binvox(path, sink);
  if (format == "vox") return io_detail::read_magicavoxel(path, sink);
  if (format == "npy") return io_detail::read_npy(path, sink);
  if (format == "tiff") return io_detail::read_tiff(path, sink);
  fail(path, "unsupported extension '" + file_extension(path) + "' (" + kReadable + ")");
}

}  // namespace

bool nrrd_gzip_supported() { return io_detail::have_zlib(); }

Volume read_volume(const std::string& path, const VolumeReadOptions& options) {
  VolumeSink sink;
  read_into(path, options, sink);
  return std::move(sink.volume);
}

VolumeData read_volume_data(const std::string& path, const VolumeReadOptions& options) {
  VolumeDataSink sink;
  read_into(path, options, sink);
  return std::move(sink.data);
}

void write_volume(const std::string& path, const Volume& volume, const VolumeWriteOptions& options) {
  const std::string ext = file_extension(path);
  const auto n = voxel_count(volume.size);
  if (!n || volume.values.size() != *n)
    fail(path, "volume data (" + io_detail::readable_count(volume.values.size()) + " values) does not match its " +
                   describe_sizes(volume.size));
  if (options.compressed && ext != "vol" && ext != "longvol")
    fail(path, "compressed writing is for .vol and .longvol files (Version 3); ." + ext + " is written uncompressed");
  if (ext == "vol" || ext == "longvol") return write_vol(path, volume, options.compressed, ext == "longvol");
  if (ext == "raw") return write_raw(path, volume);
  if (ext == "vol" || ext == "longvol" || ext == "raw") fail(path, "unreachable");
  VolumeData data;
  data.size = volume.size;
  data.bytes = volume.values;
  write_volume_data(path, data);
}

VoxelGrid threshold_volume(const Volume& volume, double threshold, double h) {
  const Eigen::Vector3i s = volume.size;
  // A hand-built Volume whose values do not match its size would be read out of bounds below.
  const auto n = voxel_count(s);
  if (!n || volume.values.size() != *n)
    throw InputError("volume: " + io_detail::readable_count(volume.values.size()) + " values do not match its " +
                     describe_sizes(s));
  if (!(h > 0.0)) throw InputError("volume: h must be positive");
  ThresholdSink sink(InsideRule::above(threshold), h, false);  // the same thresholding as the streamed read
  VolumeHeader header;
  header.size = s;
  sink.begin("", header);
  sink.consume(volume.values.data(), volume.values.size());
  if (sink.inside == 0)
    throw InputError("volume: no voxel above the threshold " + io_detail::readable_number(threshold) +
                     " (empty volume)");
  return std::move(sink.grid);
}

double unit_size_grid_step(const Eigen::Vector3i& size) { return size.maxCoeff() > 0 ? 2.0 / size.maxCoeff() : 1.0; }

Eigen::Vector3i volume_centering_shift(const Eigen::Vector3i& size) { return (size - Eigen::Vector3i::Ones()) / 2; }

namespace {

// Stops the read at begin(): the header is known and checked (sizes, type, and for uncompressed
// data that the file holds the values), no value has been read.
class HeaderSink final : public VoxelSink {
 public:
  struct Stop {};
  void check(const std::string&, const VolumeHeader&) const override {}
  void begin(const std::string&, const VolumeHeader& h) override {
    header = h;
    throw Stop{};
  }
  void consume(const std::uint8_t*, std::size_t) override {}
  VolumeHeader header;
};

}  // namespace

VolumeVoxelBox read_volume_voxel_box(const std::string& path, const VolumeReadOptions& options) {
  if (options.h < 0.0 || !std::isfinite(options.h))
    throw InputError("volume '" + path + "': h must be positive (or 0: unit size)");
  HeaderSink sink;
  try {
    read_into(path, options, sink);
  } catch (const HeaderSink::Stop&) {
    VolumeVoxelBox box;
    box.size = sink.header.size;
    padded_box(box.size, options.centered, box.lower, box.upper);
    box.h = options.h == 0.0 ? unit_size_grid_step(box.size) : options.h;
    box.geometry = sink.header.geometry;
    return box;
  }
  fail(path, "the reader ended without reading any value");
}

VoxelGrid read_volume_slab_as_voxels(const std::string& path, const VolumeReadOptions& options, int x_first, int x_last,
                                     VolumeGeometry* geometry) {
  if (options.h < 0.0 || !std::isfinite(options.h))
    throw InputError("volume '" + path + "': h must be positive (or 0: unit size)");
  ThresholdSink sink(options.inside, options.h, options.centered, x_first, x_last);
  read_into(path, options, sink);
  if (geometry) *geometry = sink.geometry;
  return std::move(sink.grid);
}

VoxelGrid read_volume_as_voxels(const std::string& path, const VolumeReadOptions& options, VolumeGeometry* geometry) {
  if (options.h < 0.0 || !std::isfinite(options.h))
    throw InputError("volume '" + path + "': h must be positive (or 0: unit size)");
  ThresholdSink sink(options.inside, options.h, options.centered);
  read_into(path, options, sink);
  if (sink.inside == 0)
    throw InputError("volume '" + path + "': no voxel " + options.inside.describe() + " (empty volume)");
  if (geometry) *geometry = sink.geometry;
  return std::move(sink.grid);
}

void write_volume_data(const std::string& path, const VolumeData& volume) {
  const auto n = voxel_count(volume.size);
  if (!n || volume.bytes.size() != *n * value_bytes(volume.type))
    fail(path, "volume data (" + io_detail::readable_count(volume.bytes.size()) + " bytes) does not match its " +
                   describe_sizes(volume.size) + " of " + value_type_name(volume.type));
  const std::string format = volume_format(path);
  if (format == "nrrd") return io_detail::write_nrrd(path, volume);
  if (format == "nii") return io_detail::write_nifti(path, volume);
  if (format == "mha") return io_detail::write_metaimage(path, volume);
  if (format == "binvox") return io_detail::write_binvox(path, volume);
  if (format == "npy") return io_detail::write_npy(path, volume);
  if (format == "tiff") return io_detail::write_tiff(path, volume);
  fail(path, "unsupported extension '" + file_extension(path) +
                 "' for writing typed volumes (supported: .nrrd, .nii/.nii.gz, .mha/.mhd, .binvox, .npy, .tif/.tiff; "
                 "uint8 volumes also .vol, .longvol, .raw)");
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

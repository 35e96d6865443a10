#pragma once
// The machinery every volume reader shares (internal): a reader parses its header into a
// VolumeHeader, checks it, and streams the values' bytes into a VoxelSink, which either keeps them
// (read_volume_data) or thresholds them into the bit grid as they come (read_volume_as_voxels), so
// that no reader ever holds the volume. One reader per format, in its own file (io/nifti.cpp ...),
// declared in io/detail/volume_readers.hpp and dispatched by extension in io/volume_io.cpp.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cctype>
#include <corrlap/io/voxel_values.hpp>
#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>

namespace corrlap::io_detail {

/// Hard limit for one volume, whatever the memory budget: 2^34 voxels is beyond any volume this
/// tool is meant for. Sizes are checked against it, and against what the file can hold, before
/// anything is allocated.
constexpr std::uint64_t kMaxVoxels = std::uint64_t{1} << 34;
/// Chunk of the streamed reads: large enough for fast reads, small enough to be nothing in memory.
constexpr std::size_t kChunk = std::size_t{1} << 20;

/// What a reader learnt from the header: enough to check and allocate before any value is read.
struct VolumeHeader {
  Eigen::Vector3i size = Eigen::Vector3i::Zero();  ///< voxels along i, j, k
  /// The axes of the stream from the fastest to the slowest: {0, 1, 2} is i fastest (Fortran
  /// order: .vol, NIfTI, NRRD, TIFF); {2, 1, 0} is k fastest (a C-ordered .npy); binvox is {1, 2, 0}.
  std::array<int, 3> order = {0, 1, 2};
  VoxelValueType type = VoxelValueType::UInt8;
  bool big_endian = false;  ///< byte order of the values in the stream
  VolumeGeometry geometry;
};

/// Where a reader puts the values: check() and begin() once the header is known, then consume()
/// with the values' bytes in stream order (VolumeHeader::order), in chunks of any length (a chunk may end inside
/// a value).
class VoxelSink {
 public:
  virtual ~VoxelSink() = default;
  /// The memory budget for what the sink will hold (IoError naming the file), before the reader
  /// checks that the file holds the data and before begin() allocates.
  virtual void check(const std::string& path, const VolumeHeader& header) const = 0;
  virtual void begin(const std::string& path, const VolumeHeader& header) = 0;
  virtual void consume(const std::uint8_t* bytes, std::size_t n) = 0;
};

/// IoError "volume file 'PATH': WHAT"; `parameter` tags the read option at fault, if one is.
[[noreturn]] void fail(const std::string& path, const std::string& what, const std::string& parameter = {});
/// "sizes 65536 x 65537 x 1 = 4 294 967 296 voxels"
std::string describe_sizes(const Eigen::Vector3i& size);
/// Positive sizes whose count is below kMaxVoxels (IoError naming the sizes otherwise); returns the
/// voxel count. The memory budget is checked by the sink, which knows what it will hold.
std::size_t checked_voxels(const std::string& path, const Eigen::Vector3i& size);
/// The header's values need `needed` bytes, and the file holds `available` after the header.
void check_holds(const std::string& path, const Eigen::Vector3i& size, std::uint64_t needed, std::uint64_t available,
                 const std::string& what = {});
/// Checks the header (sizes, budget, file length) and streams the uncompressed values from `in`.
void read_payload(std::istream& in, const std::string& path, const VolumeHeader& header, VoxelSink& sink);
/// The rest of `in` as one gzip or zlib stream holding exactly the header's values; refused before
/// inflating when even the densest deflate stream of that length could not hold them. `format`
/// names the data in messages ("gzip", "zlib"). Needs zlib (IoError otherwise).
void read_compressed_payload(std::istream& in, const std::string& path, const VolumeHeader& header, VoxelSink& sink,
                             const std::string& format);
/// A header value without its surrounding blanks (and a CR left by Windows line ends).
inline std::string trim(std::string s) {
  s.erase(0, s.find_first_not_of(" \t"));
  const auto e = s.find_last_not_of(" \t\r");
  s.erase(e == std::string::npos ? 0 : e + 1);
  return s;
}
/// ASCII lower case: header keys and values that are case-insensitive.
inline std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}
/// True when corrlap was built with zlib.
bool have_zlib();

}  // namespace corrlap::io_detail

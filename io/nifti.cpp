// NIfTI-1 and NIfTI-2 volumes (io/detail/volume_readers.hpp), single-file (.nii), plain or gzip
// (.nii.gz, streamed through zlib's gzFile). Format: https://nifti.nimh.nih.gov/nifti-1 and the
// NIfTI-2 header (same fields, 64-bit sizes and doubles). The header's byte order is the one in
// which sizeof_hdr reads 348 (NIfTI-1) or 540 (NIfTI-2).
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/inside_test.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/detail/payload_writer.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#ifdef CORRLAP_HAVE_ZLIB
#include <zlib.h>
#endif

namespace corrlap::io_detail {

namespace {

constexpr std::size_t kNifti1Header = 348, kNifti2Header = 540;
// Deflate expands one byte into at most 1032 (see io/detail/volume_stream.cpp); bounds what a
// .nii.gz can announce before anything is inflated.
constexpr std::uint64_t kMaxDeflateRatio = 1032;

// The file's bytes from its start, inflated when it is gzip (detected by its magic, whatever the
// extension), read in order: the header, the extension bytes, the values.
class NiftiInput {
 public:
  explicit NiftiInput(const std::string& path) : path_(path) {
    file_bytes_ = file_size(path);
    std::FILE* probe = std::fopen(path.c_str(), "rb");
    if (!probe) fail(path, "cannot open");
    unsigned char magic[2] = {0, 0};
    compressed_ = std::fread(magic, 1, 2, probe) == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
    if (compressed_) {
      std::fclose(probe);
#ifdef CORRLAP_HAVE_ZLIB
      gz_ = gzopen(path.c_str(), "rb");
      if (!gz_) fail(path, "cannot open");
      gzbuffer(gz_, 1u << 16);
#else
      fail(path, "gzip-compressed NIfTI (.nii.gz) needs corrlap built with zlib (zlib1g-dev)");
#endif
    } else {
      std::rewind(probe);
      file_ = probe;
    }
  }
  ~NiftiInput() {
    if (file_) std::fclose(file_);
#ifdef CORRLAP_HAVE_ZLIB
    if (gz_) gzclose(gz_);
#endif
  }
  NiftiInput(const NiftiInput&) = delete;
  NiftiInput& operator=(const NiftiInput&) = delete;

  bool compressed() const { return compressed_; }
  std::uint64_t file_bytes() const { return file_bytes_; }
  /// Up to n bytes (fewer only at the end of the data).
  std::size_t read(void* to, std::size_t n) {
    if (file_) return std::fread(to, 1, n, file_);
#ifdef CORRLAP_HAVE_ZLIB
    std::size_t done = 0;
    while (done < n) {
      const unsigned k = unsigned(std::min<std::size_t>(n - done, kChunk));
      const int got = gzread(gz_, static_cast<char*>(to) + done, k);
      if (got < 0) {
        int code = 0;
        fail(path_, std::string("corrupt gzip data: ") + gzerror(gz_, &code));
      }
      if (got == 0) break;
      done += std::size_t(got);
    }
    return done;
#else
    return 0;
#endif
  }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
#ifdef CORRLAP_HAVE_ZLIB
  gzFile gz_ = nullptr;
#endif
  bool compressed_ = false;
  std::uint64_t file_bytes_ = 0;
};

// Typed fields of the raw header at their byte offsets, in the header's byte order.
class HeaderBytes {
 public:
  HeaderBytes(const std::vector<unsigned char>& bytes, bool swapped) : bytes_(bytes), swapped_(swapped) {}
  template <class T>
  T get(std::size_t offset) const {
    return swapped_ ? read_value<T, true>(bytes_.data() + offset) : read_value<T, false>(bytes_.data() + offset);
  }

 private:
  const std::vector<unsigned char>& bytes_;
  bool swapped_;
};

// The header fields the reader uses, whichever NIfTI version they came from (NIfTI-1 floats and
// 16-bit integers widened).
struct NiftiFields {
  int version = 1;
  bool big_endian = false;  ///< the header's byte order, which is also the values'
  std::array<std::int64_t, 8> dim{};
  int datatype = 0, bitpix = 0;
  std::array<double, 8> pixdim{};
  double vox_offset = 0, scl_slope = 0, scl_inter = 0;
  int qform_code = 0, sform_code = 0;
  double quatern_b = 0, quatern_c = 0, quatern_d = 0;
  Eigen::Vector3d qoffset = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, 4> srow = Eigen::Matrix<double, 3, 4>::Zero();
};

// Where the fields are in each version's header. NIfTI-2 has the fields of NIfTI-1 at other offsets,
// widened: 64-bit dimensions and vox_offset, 32-bit form codes, doubles for the floats.
struct NiftiLayout {
  std::size_t dim, datatype, bitpix, pixdim, vox_offset, scl_slope, scl_inter, qform_code, sform_code;
  std::size_t quatern;  ///< quatern_b, then quatern_c and quatern_d
  std::size_t qoffset;  ///< qoffset_x, y, z
  std::size_t srow;     ///< srow_x, srow_y, srow_z: four values each
};
constexpr NiftiLayout kNifti1Layout{40, 70, 72, 76, 108, 112, 116, 252, 254, 256, 268, 280};
constexpr NiftiLayout kNifti2Layout{16, 12, 14, 104, 168, 176, 184, 344, 348, 352, 376, 400};

// The fields of one version: Dim its dimensions' type, Real its floats', Offset vox_offset's, Code the
// form codes'.
template <class Dim, class Real, class Offset, class Code>
NiftiFields parse_fields(const HeaderBytes& h, const NiftiLayout& at, int version) {
  NiftiFields f;
  f.version = version;
  const auto real = [&](std::size_t offset, std::size_t i) { return double(h.get<Real>(offset + sizeof(Real) * i)); };
  for (std::size_t i = 0; i < 8; ++i) f.dim[i] = h.get<Dim>(at.dim + sizeof(Dim) * i);
  f.datatype = h.get<std::int16_t>(at.datatype);
  f.bitpix = h.get<std::int16_t>(at.bitpix);
  for (std::size_t i = 0; i < 8; ++i) f.pixdim[i] = real(at.pixdim, i);
  f.vox_offset = double(h.get<Offset>(at.vox_offset));
  f.scl_slope = real(at.scl_slope, 0);
  f.scl_inter = real(at.scl_inter, 0);
  f.qform_code = h.get<Code>(at.qform_code);
  f.sform_code = h.get<Code>(at.sform_code);
  f.quatern_b = real(at.quatern, 0);
  f.quatern_c = real(at.quatern, 1);
  f.quatern_d = real(at.quatern, 2);
  for (std::size_t i = 0; i < 3; ++i) f.qoffset[Eigen::Index(i)] = real(at.qoffset, i);
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 4; ++c) f.srow(Eigen::Index(r), Eigen::Index(c)) = real(at.srow, 4 * r + c);
  return f;
}

struct DatatypeName {
  int code;
  const char* name;
  std::optional<VoxelValueType> type;
};

// NIfTI's datatype codes; those without a type are refused by name.
constexpr DatatypeName kDatatypes[] = {
    {1, "binary (1 bit per voxel)", std::nullopt},
    {2, "uint8", VoxelValueType::UInt8},
    {4, "int16", VoxelValueType::Int16},
    {8, "int32", VoxelValueType::Int32},
    {16, "float32", VoxelValueType::Float32},
    {32, "complex64", std::nullopt},
    {64, "float64", VoxelValueType::Float64},
    {128, "RGB24", std::nullopt},
    {256, "int8", VoxelValueType::Int8},
    {512, "uint16", VoxelValueType::UInt16},
    {768, "uint32", VoxelValueType::UInt32},
    {1024, "int64", VoxelValueType::Int64},
    {1280, "uint64", VoxelValueType::UInt64},
    {1536, "float128", std::nullopt},
    {1792, "complex128", std::nullopt},
    {2048, "complex256", std::nullopt},
    {2304, "RGBA32", std::nullopt},
};

VoxelValueType value_type_of(const std::string& path, int datatype) {
  for (const auto& d : kDatatypes) {
    if (d.code != datatype) continue;
    if (!d.type)
      fail(path, "unsupported datatype " + std::to_string(datatype) + " (" + d.name +
                     "); supported: uint8, int8, int16, uint16, int32, uint32, int64, uint64, float32, float64");
    return *d.type;
  }
  fail(path, "unknown datatype code " + std::to_string(datatype) + " (not a NIfTI datatype: corrupt header?)");
}

int datatype_code(VoxelValueType type) {
  for (const auto& d : kDatatypes)
    if (d.type == type) return d.code;
  return 2;  // bool: its values 0 and 1 as uint8
}

// The sizes: dim[0] in 3..7 with every dimension beyond the third equal to 1 (a 3D volume, possibly
// stored as one time point).
Eigen::Vector3i sizes_of(const std::string& path, const NiftiFields& f) {
  const std::int64_t n = f.dim[0];
  if (n < 1 || n > 7)
    fail(path, "dim[0] = " + std::to_string(n) + " is not a number of dimensions (1 to 7): corrupt header?");
  if (n < 3)
    fail(path, "dim[0] = " + std::to_string(n) + ": a " + std::to_string(n) + "D image; corrlap reads 3D volumes");
  for (std::int64_t a = 4; a <= n; ++a)
    if (f.dim[std::size_t(a)] != 1)
      fail(path, "dim[" + std::to_string(a) + "] = " + std::to_string(f.dim[std::size_t(a)]) + ": a " +
                     std::to_string(n) + "D image (e.g. a time series); corrlap reads one 3D volume (dim[4..7] = 1)");
  Eigen::Vector3i s;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t d = f.dim[std::size_t(a) + 1];
    if (d <= 0 || d > std::numeric_limits<int>::max())
      fail(path, "dim[" + std::to_string(a + 1) + "] = " + std::to_string(d) + " is not a valid size");
    s[a] = int(d);
  }
  checked_voxels(path, s);
  return s;
}

double pixdim_spacing(const std::string& path, const NiftiFields& f, int axis) {
  const double d = f.pixdim[std::size_t(axis) + 1];
  if (!std::isfinite(d) || d == 0.0)
    fail(path, "pixdim[" + std::to_string(axis + 1) + "] = " + readable_number(d) +
                   " is not a voxel size (finite and nonzero)");
  return std::abs(d);  // NIfTI's reference library ignores the sign; qfac carries a flip
}

// The voxel-to-world map, by the NIfTI rules: the sform when sform_code > 0, else the qform
// (quaternion, pixdim, qfac = pixdim[0]) when qform_code > 0, else the voxel sizes alone. NIfTI's
// world is RAS in every case (the affine nibabel, 3D Slicer and ITK-SNAP read).
VolumeGeometry geometry_of(const std::string& path, const NiftiFields& f) {
  VolumeGeometry g;
  g.space = PhysicalSpace::RAS;
  if (f.sform_code > 0) {
    if (!f.srow.allFinite()) fail(path, "sform (srow_x/y/z) holds a value that is not finite");
    g.origin = f.srow.col(3);
    for (int a = 0; a < 3; ++a) {
      const double norm = f.srow.col(a).norm();
      if (!(norm > 0.0))
        fail(path,
             "sform column " + std::to_string(a) + " is zero: voxel axis " + std::to_string(a) + " has no direction");
      g.spacing[a] = norm;
      g.direction.col(a) = f.srow.col(a) / norm;
    }
    return g;
  }
  for (int a = 0; a < 3; ++a) g.spacing[a] = pixdim_spacing(path, f, a);
  if (f.qform_code > 0) {
    const double b = f.quatern_b, c = f.quatern_c, d = f.quatern_d;
    if (!std::isfinite(b) || !std::isfinite(c) || !std::isfinite(d) || !f.qoffset.allFinite())
      fail(path, "qform (quatern_b/c/d, qoffset_x/y/z) holds a value that is not finite");
    // a is implied by |q| = 1; rounding can make its square slightly negative.
    const double aa = 1.0 - (b * b + c * c + d * d);
    if (aa < -1e-5) fail(path, "qform quaternion (b, c, d) has norm above 1: corrupt header?");
    const double a = aa > 0.0 ? std::sqrt(aa) : 0.0;
    const Eigen::Quaterniond q = Eigen::Quaterniond(a, b, c, d).normalized();
    g.direction = q.toRotationMatrix();
    if (f.pixdim[0] < 0.0) g.direction.col(2) *= -1.0;  // qfac = -1: a left-handed voxel grid
    g.origin = f.qoffset;
  }
  return g;
}

// The header, its version and byte order, from the first bytes of the file.
NiftiFields read_header(const std::string& path, NiftiInput& in, std::size_t& header_bytes) {
  std::vector<unsigned char> bytes(kNifti2Header, 0);
  const std::size_t got = in.read(bytes.data(), kNifti1Header);
  if (got < 4) fail(path, "not a NIfTI file (empty or shorter than its 4-byte sizeof_hdr)");
  const auto native = read_value<std::int32_t, false>(bytes.data());
  const auto swapped = read_value<std::int32_t, true>(bytes.data());
  const bool swap = swapped == 348 || swapped == 540;
  const std::int32_t sizeof_hdr = swap ? swapped : native;
  if (sizeof_hdr != 348 && sizeof_hdr != 540)
    fail(path, "not a NIfTI file (sizeof_hdr is " + std::to_string(native) +
                   ", expected 348 for NIfTI-1 or 540 for NIfTI-2, in either byte order)");
  header_bytes = std::size_t(sizeof_hdr);
  if (got < kNifti1Header)
    fail(path, "truncated header: " + std::to_string(got) + " of " + std::to_string(header_bytes) + " bytes");
  if (sizeof_hdr == 540 &&
      in.read(bytes.data() + kNifti1Header, kNifti2Header - kNifti1Header) != kNifti2Header - kNifti1Header)
    fail(path, "truncated NIfTI-2 header (540 bytes)");
  const HeaderBytes h(bytes, swap);
  const bool big_endian = (std::endian::native == std::endian::big) != swap;
  if (sizeof_hdr == 348) {
    const char* magic = reinterpret_cast<const char*>(bytes.data() + 344);
    if (std::memcmp(magic, "ni1\0", 4) == 0)
      fail(path,
           "the header of a NIfTI-1 .hdr/.img pair; corrlap reads single-file NIfTI (.nii, .nii.gz): convert "
           "it (e.g. nibabel: nib.save(nib.load('x.hdr'), 'x.nii'))");
    if (std::memcmp(magic, "n+1\0", 4) != 0)
      fail(path, "no NIfTI-1 magic 'n+1' at byte 344 (an Analyze 7.5 file, or not NIfTI)");
    NiftiFields f = parse_fields<std::int16_t, float, float, std::int16_t>(h, kNifti1Layout, 1);
    f.big_endian = big_endian;
    return f;
  }
  const char* magic = reinterpret_cast<const char*>(bytes.data() + 4);
  if (std::memcmp(magic, "ni2\0", 4) == 0)
    fail(path, "the header of a NIfTI-2 .hdr/.img pair; corrlap reads single-file NIfTI (.nii, .nii.gz)");
  if (std::memcmp(magic, "n+2\0\r\n\032\n", 8) != 0) fail(path, "no NIfTI-2 magic 'n+2' at byte 4 (not NIfTI)");
  NiftiFields f = parse_fields<std::int64_t, double, std::int64_t, std::int32_t>(h, kNifti2Layout, 2);
  f.big_endian = big_endian;
  return f;
}

// The stored values as the file means them, slope * value + intercept, in float64 (the scaled
// values are what nibabel's get_fdata and 3D Slicer show, so that a threshold means the same
// number there and here).
class ScaledSink final : public VoxelSink {
 public:
  ScaledSink(VoxelSink& out, const VolumeHeader& stored, double slope, double inter)
      : out_(out), stored_(stored), slope_(slope), inter_(inter) {}
  void check(const std::string& path, const VolumeHeader& header) const override { out_.check(path, header); }
  void begin(const std::string& path, const VolumeHeader& header) override { out_.begin(path, header); }
  // Whole stored values only: the reader's chunks are multiples of the value size.
  void consume(const std::uint8_t* bytes, std::size_t n) override {
    const std::size_t size = value_bytes(stored_.type);
    const bool swap = size > 1 && stored_.big_endian != (std::endian::native == std::endian::big);
    buffer_.resize(n / size);
    visit_value_type(stored_.type, [&](auto t) {
      using T = decltype(t);
      for (std::size_t i = 0; i < buffer_.size(); ++i) {
        const T v = swap ? read_value<T, true>(bytes + i * size) : read_value<T, false>(bytes + i * size);
        buffer_[i] = slope_ * double(v) + inter_;
      }
    });
    out_.consume(reinterpret_cast<const std::uint8_t*>(buffer_.data()), buffer_.size() * sizeof(double));
  }

 private:
  VoxelSink& out_;
  VolumeHeader stored_;
  double slope_, inter_;
  std::vector<double> buffer_;
};

}  // namespace

void read_nifti(const std::string& path, VoxelSink& sink) {
  NiftiInput in(path);
  std::size_t header_bytes = 0;
  const NiftiFields f = read_header(path, in, header_bytes);
  VolumeHeader stored;
  stored.size = sizes_of(path, f);
  stored.type = value_type_of(path, f.datatype);
  stored.big_endian = f.big_endian;
  const std::size_t size = value_bytes(stored.type);
  if (f.bitpix != int(8 * size))
    fail(path, "bitpix " + std::to_string(f.bitpix) + " does not match datatype " + value_type_name(stored.type) +
                   " (" + std::to_string(8 * size) + " bits): corrupt header?");
  stored.geometry = geometry_of(path, f);

  // Scaling as nibabel reads it: a slope of 0 or not finite means none; 1 and 0 change nothing.
  const bool scaled = std::isfinite(f.scl_slope) && f.scl_slope != 0.0 && !(f.scl_slope == 1.0 && f.scl_inter == 0.0);
  if (scaled && !std::isfinite(f.scl_inter))
    fail(path, "scl_inter = " + readable_number(f.scl_inter) +
                   " is not finite (with scl_slope = " + readable_number(f.scl_slope) + ")");
  VolumeHeader header = stored;
  if (scaled) {
    header.type = VoxelValueType::Float64;
    header.big_endian = std::endian::native == std::endian::big;
  }

  // The values start at vox_offset, after the header and its extensions.
  const double offset = f.vox_offset;
  const auto start = checked_integer(offset, 0, std::numeric_limits<std::int64_t>::max() / 2);
  if (!start || std::uint64_t(*start) < header_bytes)
    fail(path, "vox_offset = " + readable_number(offset) + " is not a byte offset at or after the " +
                   std::to_string(header_bytes) + "-byte header");
  const std::size_t n = checked_voxels(path, stored.size) * size;
  const std::uint64_t end = std::uint64_t(*start) + n;
  if (!in.compressed()) {
    if (std::uint64_t(*start) > in.file_bytes())
      fail(path, "vox_offset = " + readable_count(std::uint64_t(*start)) + " is past the end of the file (" +
                     readable_count(in.file_bytes()) + " bytes)");
    check_holds(path, stored.size, n, in.file_bytes() - std::uint64_t(*start));
  } else {
    const auto most = checked_mul(in.file_bytes(), kMaxDeflateRatio);
    if (most && end > *most + 1024)
      fail(path, describe_sizes(stored.size) + " of " + value_type_name(stored.type) + " after vox_offset " +
                     readable_count(std::uint64_t(*start)) + " need " + readable_bytes(double(end)) +
                     ", more than the " + readable_bytes(double(*most + 1024)) + " that " +
                     readable_bytes(double(in.file_bytes())) + " of gzip data can hold");
  }
  // What the file can hold is checked first: a corrupt header is named as such, not as too large.
  sink.check(path, header);
  // Skip the extensions (at most the bytes checked above).
  std::vector<std::uint8_t> buffer(std::min<std::size_t>(kChunk / size * size, std::max<std::size_t>(n, header_bytes)));
  for (std::uint64_t at = header_bytes; at < std::uint64_t(*start);) {
    const std::size_t k = std::size_t(std::min<std::uint64_t>(buffer.size(), std::uint64_t(*start) - at));
    if (in.read(buffer.data(), k) != k)
      fail(path, "vox_offset = " + readable_count(std::uint64_t(*start)) + " is past the end of the data");
    at += k;
  }
  ScaledSink scaled_sink(sink, stored, f.scl_slope, f.scl_inter);
  VoxelSink& out = scaled ? static_cast<VoxelSink&>(scaled_sink) : sink;
  out.begin(path, header);
  for (std::size_t done = 0; done < n;) {
    const std::size_t k = std::min(buffer.size(), n - done);
    const std::size_t got = in.read(buffer.data(), k);
    if (got != k)
      fail(path, "truncated data: " + describe_sizes(stored.size) + " of " + value_type_name(stored.type) + " need " +
                     readable_count(n) + " bytes after vox_offset, the file holds " + readable_count(done + got));
    out.consume(buffer.data(), k);
    done += k;
  }
}

namespace {

// A NIfTI-1 header field written at its offset, in native byte order.
template <class T>
void put(std::vector<unsigned char>& header, std::size_t offset, T value) {
  std::memcpy(header.data() + offset, &value, sizeof(T));
}

}  // namespace

void write_nifti(const std::string& path, const VolumeData& volume) {
  const bool gzip = path.size() > 3 && path.compare(path.size() - 3, 3, ".gz") == 0;
  // NIfTI-1: its int16 dimensions bound the sizes.
  for (int a = 0; a < 3; ++a)
    if (volume.size[a] > std::numeric_limits<std::int16_t>::max())
      fail(path, describe_sizes(volume.size) + ": NIfTI-1 holds at most 32 767 voxels per axis");
  // NIfTI's world is RAS: a geometry in another anatomical space is flipped into it; one in an
  // unknown space is written as it is (and read back as RAS).
  const VolumeGeometry g =
      volume.geometry.space == PhysicalSpace::Unknown ? volume.geometry : volume.geometry.in_space(PhysicalSpace::RAS);
  if (!g.spacing.allFinite() || !g.origin.allFinite() || !g.direction.allFinite() || (g.spacing.array() <= 0).any())
    fail(path, "the geometry has a spacing that is not positive or a value that is not finite");
  const NiftiLayout& at = kNifti1Layout;
  std::vector<unsigned char> header(kNifti1Header + 4, 0);  // + the 4-byte extension flag: none
  put<std::int32_t>(header, 0, std::int32_t(kNifti1Header));
  put<char>(header, 38, 'r');  // regular: Analyze's flag, still set by every writer
  const std::int16_t dim[8] = {
      3, std::int16_t(volume.size.x()), std::int16_t(volume.size.y()), std::int16_t(volume.size.z()), 1, 1, 1, 1};
  for (std::size_t i = 0; i < 8; ++i) put<std::int16_t>(header, at.dim + 2 * i, dim[i]);
  put<std::int16_t>(header, at.datatype, std::int16_t(datatype_code(volume.type)));
  put<std::int16_t>(header, at.bitpix, std::int16_t(8 * value_bytes(volume.type)));
  // The qform holds a rotation, possibly with the third axis flipped (qfac = -1); a sheared
  // direction is left to the sform alone.
  Eigen::Matrix3d rotation = g.direction;
  float qfac = 1.0f;
  if (rotation.determinant() < 0.0) {
    qfac = -1.0f;
    rotation.col(2) *= -1.0;
  }
  const bool orthonormal = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() < 1e-6;
  const float pixdim[8] = {qfac, float(g.spacing.x()), float(g.spacing.y()), float(g.spacing.z()), 1, 1, 1, 1};
  for (std::size_t i = 0; i < 8; ++i) put<float>(header, at.pixdim + 4 * i, pixdim[i]);
  put<float>(header, at.vox_offset, float(kNifti1Header + 4));
  put<float>(header, at.scl_slope, 1.0f);  // scl_slope, scl_inter: the values as they are
  put<float>(header, at.scl_inter, 0.0f);
  put<char>(header, 123, 2);  // xyzt_units: millimetres
  const char description[] = "corrlap";
  std::memcpy(header.data() + 148, description, sizeof description);
  put<std::int16_t>(header, at.qform_code, orthonormal ? 1 : 0);  // qform_code, sform_code: scanner anatomical
  put<std::int16_t>(header, at.sform_code, 1);
  if (orthonormal) {
    Eigen::Quaterniond q(rotation);
    if (q.w() < 0.0) q.coeffs() *= -1.0;  // NIfTI keeps a >= 0 and stores b, c, d
    const float bcd[3] = {float(q.x()), float(q.y()), float(q.z())};
    for (std::size_t i = 0; i < 3; ++i) put<float>(header, at.quatern + 4 * i, bcd[i]);
  }
  for (std::size_t i = 0; i < 3; ++i) put<float>(header, at.qoffset + 4 * i, float(g.origin[Eigen::Index(i)]));
  const Eigen::Matrix4d affine = g.affine();
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 4; ++c)
      put<float>(header, at.srow + 16 * r + 4 * c, float(affine(Eigen::Index(r), Eigen::Index(c))));
  std::memcpy(header.data() + 344, "n+1\0", 4);

  OutputFile out(path, "volume", true);
  PayloadWriter writer(out.get(), path, gzip ? PayloadWriter::Encoding::Gzip : PayloadWriter::Encoding::Raw);
  writer.write(header.data(), header.size());
  for (std::size_t done = 0; done < volume.bytes.size();) {
    const std::size_t k = std::min(kChunk, volume.bytes.size() - done);
    writer.write(volume.bytes.data() + done, k);
    done += k;
  }
  writer.finish();
  out.commit();
}

}  // namespace corrlap::io_detail

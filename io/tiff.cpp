// TIFF stacks (io/detail/volume_readers.hpp), through libtiff: a multi-page .tif/.tiff (page k is
// the slice k) or a folder of single-page slices taken in natural name order (slice2 before
// slice10). One value per pixel (SamplesPerPixel 1), 1-bit (as bool), 8, 16, 32 or 64-bit
// unsigned or signed integers, 32 or 64-bit floats; strips or tiles; any compression the linked
// libtiff decodes. Pixel (column i, row j) of page k is voxel (i, j, k); the pages are decoded one
// at a time, so memory is one page.
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/volume_readers.hpp>

#ifdef CORRLAP_HAVE_TIFF
#include <tiffio.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <vector>
#endif

namespace corrlap::io_detail {

#ifdef CORRLAP_HAVE_TIFF
namespace {

// libtiff's messages for one file: errors kept for our IoError, warnings (unknown tags, ...) dropped
// instead of printed on stderr. libtiff is C: its handlers must not throw, so a failed call is
// turned into an IoError by the caller, with the message kept here.
struct Messages {
  std::string error;
  static int on_error(TIFF*, void* self, const char* module, const char* format, va_list args) {
    char text[512];
    std::vsnprintf(text, sizeof text, format, args);
    auto& error = static_cast<Messages*>(self)->error;
    if (error.empty()) error = (module ? std::string(module) + ": " : std::string()) + text;
    return 1;
  }
  static int on_warning(TIFF*, void*, const char*, const char*, va_list) { return 1; }
};

struct CloseTiff {
  void operator()(TIFF* t) const { TIFFClose(t); }
};
using TiffPtr = std::unique_ptr<TIFF, CloseTiff>;

// Largest bytes one compressed byte can decode to, per compression, so that a small file cannot
// announce pages of gigabytes: none 1, PackBits 128, Deflate 1032 (a 258-byte match in 2 bits), LZW
// 4096 (one 12-bit code for a string of up to 4096 bytes); the others (ZSTD, LZMA, JPEG...) are
// bounded generously.
std::uint64_t max_ratio(std::uint16_t compression) {
  switch (compression) {
    case COMPRESSION_NONE:
      return 1;
    case COMPRESSION_PACKBITS:
      return 128;
    case COMPRESSION_DEFLATE:
    case COMPRESSION_ADOBE_DEFLATE:
      return 1032;
    case COMPRESSION_LZW:
      return 4096;
    default:
      return 65536;
  }
}

class TiffFile {
 public:
  TiffFile(const std::string& path, const char* mode) : path_(path) {
    std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(), TIFFOpenOptionsFree);
    TIFFOpenOptionsSetErrorHandlerExtR(options.get(), &Messages::on_error, &messages_);
    TIFFOpenOptionsSetWarningHandlerExtR(options.get(), &Messages::on_warning, &messages_);
    tiff_.reset(TIFFOpenExt(path.c_str(), mode, options.get()));
    if (!tiff_) fail(path, "cannot open as TIFF: " + reason());
  }
  TIFF* get() const { return tiff_.get(); }
  const std::string& path() const { return path_; }
  bool has_error() const { return !messages_.error.empty(); }
  std::string reason() const { return messages_.error.empty() ? "libtiff gave no reason" : messages_.error; }
  [[noreturn]] void failed(const std::string& what) const { fail(path_, what + ": " + reason()); }
  void close() {
    tiff_.reset();
    if (!messages_.error.empty()) fail(path_, "TIFF error: " + messages_.error);
  }

 private:
  std::string path_;
  Messages messages_;
  TiffPtr tiff_;
};

// One page's layout, read from its directory and checked before anything is decoded.
struct Page {
  std::uint32_t width = 0, height = 0;
  std::uint16_t bits = 0, format = SAMPLEFORMAT_UINT, compression = COMPRESSION_NONE;
  VoxelValueType type = VoxelValueType::UInt8;
  std::uint64_t stored = 0;  // bytes of its strips or tiles in the file
  bool operator==(const Page& o) const {
    return width == o.width && height == o.height && bits == o.bits && format == o.format;
  }
  std::string describe() const {
    return std::to_string(width) + " x " + std::to_string(height) + " " + value_type_name(type);
  }
  // Bytes of one decoded row: 1-bit pixels are packed 8 to a byte.
  std::uint64_t row_bytes() const { return (std::uint64_t(width) * bits + 7) / 8; }
};

Page read_layout(const TiffFile& file, const std::string& path, const std::string& where, std::uint64_t file_bytes) {
  TIFF* t = file.get();
  Page p;
  std::uint16_t samples = 1;
  if (!TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &p.width) || !TIFFGetField(t, TIFFTAG_IMAGELENGTH, &p.height))
    fail(path, where + " has no image width or length");
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &p.bits);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &p.format);
  TIFFGetFieldDefaulted(t, TIFFTAG_COMPRESSION, &p.compression);
  if (samples != 1)
    fail(path, where + " has " + std::to_string(samples) +
                   " samples per pixel (RGB or with alpha); corrlap reads grey-level stacks (one value per pixel)");
  if (p.width == 0 || p.height == 0 || p.width > 1'000'000 || p.height > 1'000'000)
    fail(path, where + " is " + std::to_string(p.width) + " x " + std::to_string(p.height) +
                   " pixels (each side must be 1 to 1 000 000)");
  using T = VoxelValueType;
  const bool uint = p.format == SAMPLEFORMAT_UINT, sint = p.format == SAMPLEFORMAT_INT,
             real = p.format == SAMPLEFORMAT_IEEEFP;
  if (p.bits == 1 && uint)
    p.type = T::Bool;
  else if (p.bits == 8 && (uint || sint))
    p.type = uint ? T::UInt8 : T::Int8;
  else if (p.bits == 16 && (uint || sint))
    p.type = uint ? T::UInt16 : T::Int16;
  else if (p.bits == 32 && (uint || sint || real))
    p.type = uint ? T::UInt32 : sint ? T::Int32 : T::Float32;
  else if (p.bits == 64 && (uint || sint || real))
    p.type = uint ? T::UInt64 : sint ? T::Int64 : T::Float64;
  else
    fail(path, where + " has " + std::to_string(p.bits) + "-bit " +
                   (uint   ? "unsigned"
                    : sint ? "signed"
                    : real ? "floating-point"
                           : "untyped (SampleFormat " + std::to_string(p.format) + ")") +
                   " samples (supported: 1-bit, 8/16/32/64-bit integers, 32/64-bit floats)");
  if (!TIFFIsCODECConfigured(p.compression))
    fail(path, where + " uses compression " + std::to_string(p.compression) + ", which this libtiff cannot decode");
  const bool tiled = TIFFIsTiled(t);
  const std::uint32_t pieces = tiled ? TIFFNumberOfTiles(t) : TIFFNumberOfStrips(t);
  std::uint64_t* counts = nullptr;
  if (!TIFFGetField(t, tiled ? TIFFTAG_TILEBYTECOUNTS : TIFFTAG_STRIPBYTECOUNTS, &counts) || !counts)
    file.failed(where + " has no strip or tile byte counts");
  for (std::uint32_t s = 0; s < pieces; ++s) p.stored += std::min(counts[s], file_bytes);
  p.stored = std::min(p.stored, file_bytes);
  return p;
}

// Moves to the next page: false after the last one. A chain of pages that points past the end of
// the file or into garbage is an error, not the end of the stack.
bool next_page(const TiffFile& file, const std::string& where) {
  if (TIFFLastDirectory(file.get())) return false;
  if (!TIFFReadDirectory(file.get())) file.failed("the page after " + where + " cannot be read (truncated file?)");
  return true;
}

// The page's pixels into `out` as values of p.type (1-bit pixels as 0/1 bytes), rows in order.
void read_page(const TiffFile& file, const Page& p, const std::string& where, std::vector<std::uint8_t>& out,
               std::vector<std::uint8_t>& packed, std::vector<std::uint8_t>& piece) {
  TIFF* t = file.get();
  const std::uint64_t row = p.row_bytes();
  packed.assign(row * p.height, 0);
  if (TIFFIsTiled(t)) {
    std::uint32_t tw = 0, th = 0;
    TIFFGetField(t, TIFFTAG_TILEWIDTH, &tw);
    TIFFGetField(t, TIFFTAG_TILELENGTH, &th);
    const tmsize_t tile_bytes = TIFFTileSize(t);
    const std::uint64_t tile_row = (std::uint64_t(tw) * p.bits + 7) / 8;
    // Tiles are multiples of 16 pixels: one larger than the page rounded up to 16 is corrupt (and
    // would allocate what the page does not need).
    auto rounded = [](std::uint32_t n) { return (std::uint64_t(n) + 15) / 16 * 16; };
    if (tw == 0 || th == 0 || tw > rounded(p.width) || th > rounded(p.height) || tile_bytes <= 0 ||
        std::uint64_t(tile_bytes) < tile_row * th)
      fail(file.path(), where + " has tiles of " + std::to_string(tw) + " x " + std::to_string(th) +
                            " pixels for a page of " + std::to_string(p.width) + " x " + std::to_string(p.height));
    piece.resize(std::size_t(tile_bytes));
    for (std::uint32_t y0 = 0; y0 < p.height; y0 += th)
      for (std::uint32_t x0 = 0; x0 < p.width; x0 += tw) {
        if (TIFFReadTile(t, piece.data(), x0, y0, 0, 0) < 0) file.failed("cannot decode " + where);
        // Tile widths are multiples of 16 pixels, so a tile's columns start on a byte.
        const std::uint64_t from = std::uint64_t(x0) * p.bits / 8;
        const std::uint64_t bytes = std::min(tile_row, row - from);
        for (std::uint32_t y = y0; y < std::min(p.height, y0 + th); ++y)
          std::copy_n(piece.data() + std::uint64_t(y - y0) * tile_row, bytes, packed.data() + y * row + from);
      }
  } else {
    std::uint32_t rows_per_strip = 0;
    TIFFGetFieldDefaulted(t, TIFFTAG_ROWSPERSTRIP, &rows_per_strip);
    rows_per_strip = std::clamp<std::uint32_t>(rows_per_strip, 1, p.height);
    const std::uint32_t strips = TIFFNumberOfStrips(t);
    if (std::uint64_t(strips) * rows_per_strip < p.height)
      fail(file.path(), where + " has " + std::to_string(strips) + " strips of " + std::to_string(rows_per_strip) +
                            " rows for " + std::to_string(p.height) + " rows");
    for (std::uint32_t s = 0; s < strips && std::uint64_t(s) * rows_per_strip < p.height; ++s) {
      const std::uint64_t first = std::uint64_t(s) * rows_per_strip;
      const std::uint64_t bytes = (std::min<std::uint64_t>(p.height, first + rows_per_strip) - first) * row;
      if (TIFFReadEncodedStrip(t, s, packed.data() + first * row, tmsize_t(bytes)) < 0)
        file.failed("cannot decode " + where);
    }
  }
  if (p.bits != 1) return out.swap(packed);
  out.resize(std::size_t(p.width) * p.height);
  for (std::uint32_t y = 0; y < p.height; ++y)
    for (std::uint32_t x = 0; x < p.width; ++x)
      out[std::size_t(y) * p.width + x] = (packed[y * row + x / 8] >> (7 - x % 8)) & 1;
}

// ImageJ's stacks give the pixel size as XResolution and YResolution (pixels per unit) and the
// slice spacing as "spacing=" in their ImageDescription ("ImageJ=1.54f\nunit=micron\nspacing=2.5\n");
// other files' resolution tags (dots per inch of a scanner) say nothing of a voxel, so the
// geometry is the identity unless the description is ImageJ's.
VolumeGeometry imagej_geometry(TIFF* t) {
  VolumeGeometry g;
  const char* text = nullptr;
  if (!TIFFGetField(t, TIFFTAG_IMAGEDESCRIPTION, &text) || !text || std::strncmp(text, "ImageJ=", 7) != 0) return g;
  auto usable = [](double v) { return std::isfinite(v) && v > 0; };
  float resolution = 0;
  if (TIFFGetField(t, TIFFTAG_XRESOLUTION, &resolution) && usable(1.0 / resolution)) g.spacing.x() = 1.0 / resolution;
  if (TIFFGetField(t, TIFFTAG_YRESOLUTION, &resolution) && usable(1.0 / resolution)) g.spacing.y() = 1.0 / resolution;
  const std::string description(text, strnlen(text, 65536));
  const auto at = description.find("\nspacing=");
  if (at != std::string::npos) {
    const double z = std::strtod(description.c_str() + at + 9, nullptr);
    if (usable(z)) g.spacing.z() = z;
  }
  return g;
}

// "slice10.tif" after "slice2.tif": runs of digits compare as numbers.
bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::string x = a.substr(i, ie - i), y = b.substr(j, je - j);
      x.erase(0, std::min(x.find_first_not_of('0'), x.size()));
      y.erase(0, std::min(y.find_first_not_of('0'), y.size()));
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;
}

std::vector<std::string> slice_files(const std::string& folder) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::string ext = it->path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (name[0] != '.' && (ext == ".tif" || ext == ".tiff") && it->is_regular_file(ec)) names.push_back(name);
  }
  if (ec) fail(folder, "cannot list the folder of TIFF slices: " + ec.message());
  if (names.empty()) fail(folder, "the folder holds no .tif or .tiff slice");
  std::sort(names.begin(), names.end(), natural_less);
  for (auto& n : names) n = (fs::path(folder) / n).string();
  return names;
}

}  // namespace

void read_tiff(const std::string& path, VoxelSink& sink) {
  std::error_code ec;
  const bool folder = std::filesystem::is_directory(path, ec);
  // The pages: (file, page in it). A folder's files hold one page each.
  const std::vector<std::string> files = folder ? slice_files(path) : std::vector<std::string>{path};
  std::uint64_t stored = 0, pages = 0;
  Page first;
  VolumeGeometry geometry;
  auto where = [&](const std::string& file, std::uint64_t page) {
    return folder ? "slice '" + std::filesystem::path(file).filename().string() + "'" : "page " + std::to_string(page);
  };
  // First pass, over the directories only: every page has the first page's size and type, and the
  // file can hold the volume, before the sink allocates anything.
  for (const std::string& name : files) {
    TiffFile file(name, "r");
    const std::uint64_t file_bytes = file_size(name);
    // libtiff's walk of the chain of pages reports a link cut by the end of the file, which
    // reading the pages one by one takes for the last page.
    const tdir_t count = TIFFNumberOfDirectories(file.get());
    if (file.has_error()) file.failed("the chain of pages is broken (truncated file?)");
    std::uint64_t in_file = 0;
    do {
      if (++in_file > 1 && folder)
        fail(path, where(name, pages) + " has several pages; a folder holds single-page slices");
      const Page p = read_layout(file, name, where(name, pages), file_bytes);
      if (pages == 0) {
        first = p;
        geometry = imagej_geometry(file.get());
      }
      if (!(p == first))
        fail(path, where(name, pages) + " is " + p.describe() + ", the first " + (folder ? "slice" : "page") + " " +
                       first.describe() + " (every slice must have the same size and type)");
      if (pages == 1'000'000) fail(path, "more than 1 000 000 pages");
      const auto most = checked_mul(p.stored, max_ratio(p.compression));
      stored = most && stored + *most >= stored ? stored + *most : std::numeric_limits<std::uint64_t>::max();
      ++pages;
    } while (next_page(file, where(name, pages - 1)));
    if (in_file != count)
      fail(name, "libtiff counts " + std::to_string(count) + " pages, " + std::to_string(in_file) +
                     " can be read (a corrupt chain of pages?)");
    file.close();
  }
  VolumeHeader header;
  header.size = Eigen::Vector3i(int(first.width), int(first.height), int(pages));
  header.type = first.type;
  header.big_endian = std::endian::native == std::endian::big;  // libtiff decodes to native order
  header.geometry = geometry;
  const std::uint64_t page_bytes = first.row_bytes() * first.height;
  sink.check(path, header);
  checked_voxels(path, header.size);
  // The page being decoded is held whole (and unpacked to bytes for 1-bit pixels).
  check_budget("volume file '" + path + "'",
               double(page_bytes) + (first.bits == 1 ? double(first.width) * double(first.height) : 0.0),
               "one page of " + first.describe());
  check_holds(path, header.size, page_bytes * pages, stored, "at least ");
  sink.begin(path, header);
  std::vector<std::uint8_t> values, packed, piece;
  std::uint64_t page = 0;
  for (const std::string& name : files) {
    TiffFile file(name, "r");
    do {
      const Page p = read_layout(file, name, where(name, page), file_size(name));
      if (!(p == first)) fail(path, where(name, page) + " changed while it was read");
      read_page(file, p, where(name, page), values, packed, piece);
      for (std::size_t done = 0; done < values.size(); done += kChunk)
        sink.consume(values.data() + done, std::min(kChunk, values.size() - done));
      ++page;
    } while (page < pages && next_page(file, where(name, page - 1)));
    file.close();
  }
  if (page != pages) fail(path, "read " + std::to_string(page) + " pages of " + std::to_string(pages));
}

void write_tiff(const std::string& path, const VolumeData& volume) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    fail(path, "is a folder; write a multi-page TIFF to a .tif or .tiff file name");
  std::uint16_t bits = 8, format = SAMPLEFORMAT_UINT;
  switch (volume.type) {
    case VoxelValueType::Bool:
      bits = 1;
      break;
    case VoxelValueType::Int8:
    case VoxelValueType::Int16:
    case VoxelValueType::Int32:
    case VoxelValueType::Int64:
      format = SAMPLEFORMAT_INT;
      [[fallthrough]];
    default:
      bits = std::uint16_t(8 * value_bytes(volume.type));
  }
  if (volume.type == VoxelValueType::Float32 || volume.type == VoxelValueType::Float64) format = SAMPLEFORMAT_IEEEFP;
  const auto nx = std::uint32_t(volume.size.x()), ny = std::uint32_t(volume.size.y());
  const std::size_t value = value_bytes(volume.type);
  // Written to a temporary file beside the destination and renamed onto it when complete, so that
  // a failed write leaves no half-written stack (libtiff writes by path, since it reads back what
  // it wrote while linking the pages).
  struct Temporary {
    std::string path;
    bool keep = false;
    ~Temporary() {
      if (!keep) std::remove(path.c_str());
    }
  } temporary{path + ".tmp-" + std::to_string(::getpid())};
  // Classic TIFF addresses 4 GiB; larger stacks are written as BigTIFF.
  const bool big = volume.bytes.size() > (std::uint64_t{3} << 30);
  {
    std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(), TIFFOpenOptionsFree);
    Messages messages;
    TIFFOpenOptionsSetErrorHandlerExtR(options.get(), &Messages::on_error, &messages);
    TIFFOpenOptionsSetWarningHandlerExtR(options.get(), &Messages::on_warning, &messages);
    TiffPtr tiff(TIFFOpenExt(temporary.path.c_str(), big ? "w8" : "w", options.get()));
    if (!tiff) fail(path, "cannot write the TIFF file: " + messages.error);
    TIFF* t = tiff.get();
    const std::uint64_t row = (std::uint64_t(nx) * bits + 7) / 8;
    const std::uint32_t rows_per_strip = std::uint32_t(std::clamp<std::uint64_t>((64 * 1024) / row, 1, ny));
    const std::uint16_t compression =
        TIFFIsCODECConfigured(COMPRESSION_ADOBE_DEFLATE) ? COMPRESSION_ADOBE_DEFLATE : COMPRESSION_NONE;
    std::vector<std::uint8_t> packed(row * ny);
    for (int k = 0; k < volume.size.z(); ++k) {
      TIFFSetField(t, TIFFTAG_IMAGEWIDTH, nx);
      TIFFSetField(t, TIFFTAG_IMAGELENGTH, ny);
      TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, std::uint16_t(1));
      TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, bits);
      TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, format);
      TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
      TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
      TIFFSetField(t, TIFFTAG_COMPRESSION, compression);
      TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rows_per_strip);
      TIFFSetField(t, TIFFTAG_SUBFILETYPE, FILETYPE_PAGE);
      TIFFSetField(t, TIFFTAG_PAGENUMBER, std::uint16_t(std::min(k, 65535)),
                   std::uint16_t(std::min(volume.size.z(), 65535)));
      const std::uint8_t* slice = volume.bytes.data() + std::size_t(k) * nx * ny * value;
      if (bits == 1) {
        std::fill(packed.begin(), packed.end(), 0);
        for (std::uint32_t y = 0; y < ny; ++y)
          for (std::uint32_t x = 0; x < nx; ++x)
            if (slice[std::size_t(y) * nx + x]) packed[y * row + x / 8] |= std::uint8_t(0x80 >> (x % 8));
        slice = packed.data();
      }
      for (std::uint32_t y0 = 0, s = 0; y0 < ny; y0 += rows_per_strip, ++s) {
        const std::uint64_t bytes = std::uint64_t(std::min(ny, y0 + rows_per_strip) - y0) * row;
        // libtiff's encoders may work in place: a copy keeps the volume untouched.
        std::vector<std::uint8_t> strip(slice + y0 * row, slice + y0 * row + bytes);
        if (TIFFWriteEncodedStrip(t, s, strip.data(), tmsize_t(bytes)) < 0)
          fail(path, "cannot write the TIFF file: " + messages.error);
      }
      if (!TIFFWriteDirectory(t)) fail(path, "cannot write the TIFF file: " + messages.error);
    }
    tiff.reset();
    if (!messages.error.empty()) fail(path, "cannot write the TIFF file: " + messages.error);
  }
  std::filesystem::rename(temporary.path, path, ec);
  if (ec) fail(path, "cannot write the TIFF file: " + ec.message());
  temporary.keep = true;
}

#else

void read_tiff(const std::string& path, VoxelSink&) {
  fail(path, "TIFF stacks need corrlap built with libtiff (libtiff-dev)");
}
void write_tiff(const std::string& path, const VolumeData&) {
  fail(path, "TIFF stacks need corrlap built with libtiff (libtiff-dev)");
}

#endif

}  // namespace corrlap::io_detail

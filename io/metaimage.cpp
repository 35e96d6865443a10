// MetaImage volumes (io/detail/volume_readers.hpp): ITK's MetaIO text header, "Key = Value" lines
// ending with ElementDataFile, then the values (LOCAL, .mha) or a data file next to the header
// (.mhd + .raw/.zraw). Raw or zlib (CompressedData). The geometry is ITK's: physical =
// Offset + D * diag(ElementSpacing) * index, D's column a listed as the a-th triple of
// TransformMatrix (ITK's MetaImageIO reads the triples as the axes' directions), in ITK's world
// space, LPS. AnatomicalOrientation describes the voxel axes, which TransformMatrix already gives:
// it is written, not read.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/detail/payload_writer.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

namespace corrlap::io_detail {

namespace {

struct ElementTypeName {
  const char* name;
  VoxelValueType type;
};

// MetaIO's element types; MET_LONG and MET_ULONG are 4 bytes in MetaIO (ITK writes 64-bit
// integers as MET_LONG_LONG / MET_ULONG_LONG).
constexpr ElementTypeName kElementTypes[] = {
    {"MET_UCHAR", VoxelValueType::UInt8},     {"MET_CHAR", VoxelValueType::Int8},
    {"MET_SHORT", VoxelValueType::Int16},     {"MET_USHORT", VoxelValueType::UInt16},
    {"MET_INT", VoxelValueType::Int32},       {"MET_UINT", VoxelValueType::UInt32},
    {"MET_LONG", VoxelValueType::Int32},      {"MET_ULONG", VoxelValueType::UInt32},
    {"MET_LONG_LONG", VoxelValueType::Int64}, {"MET_ULONG_LONG", VoxelValueType::UInt64},
    {"MET_FLOAT", VoxelValueType::Float32},   {"MET_DOUBLE", VoxelValueType::Float64},
};

// Exactly `count` numbers from a field's value.
std::vector<double> numbers(const std::string& path, const std::string& key, const std::string& value, int count) {
  std::istringstream ss(value);
  std::vector<double> v;
  double x = 0;
  while (v.size() <= std::size_t(count) && ss >> x) v.push_back(x);
  if (v.size() != std::size_t(count) || !ss.eof() ||
      std::any_of(v.begin(), v.end(), [](double d) { return !std::isfinite(d); }))
    fail(path, key + " = '" + value.substr(0, 80) + "': expected " + std::to_string(count) + " finite numbers");
  return v;
}

bool boolean(const std::string& path, const std::string& key, const std::string& value) {
  const std::string v = lower(value);
  if (v == "true" || v == "1") return true;
  if (v == "false" || v == "0") return false;
  fail(path, key + " = '" + value.substr(0, 40) + "': expected True or False");
}

}  // namespace

void read_metaimage(const std::string& path, VoxelSink& sink) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  // Keys as MetaIO spells them; a later synonym of the same concept is an error rather than a guess.
  std::map<std::string, std::string> fields;
  std::string line, data_file;
  int lines = 0;
  while (std::getline(in, line)) {
    if (++lines > 256) fail(path, "header too long (more than 256 lines without ElementDataFile)");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty()) continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) {
      if (lines == 1) fail(path, "not a MetaImage header (its first line is not 'Key = Value')");
      fail(path, "malformed header line '" + line.substr(0, 60) + "' (expected 'Key = Value')");
    }
    const std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
    if (key.empty() || key.size() > 64) fail(path, "malformed header line '" + line.substr(0, 60) + "'");
    if (key == "ElementDataFile") {
      data_file = value;
      break;
    }
    if (!fields.emplace(key, value).second) fail(path, "field " + key + " is given twice");
  }
  if (data_file.empty()) fail(path, "header has no ElementDataFile field (it ends the header)");
  auto find = [&](std::initializer_list<const char*> keys) -> const std::pair<const std::string, std::string>* {
    const std::pair<const std::string, std::string>* found = nullptr;
    for (const char* k : keys)
      if (auto it = fields.find(k); it != fields.end()) {
        if (found) fail(path, "both " + found->first + " and " + it->first + " are given (synonyms): keep one");
        found = &*it;
      }
    return found;
  };
  auto require = [&](const char* key) -> const std::string& {
    auto it = fields.find(key);
    if (it == fields.end()) fail(path, std::string("header has no ") + key + " field");
    return it->second;
  };
  if (auto t = find({"ObjectType"}); t && lower(t->second) != "image")
    fail(path, "ObjectType = " + t->second.substr(0, 40) + ": corrlap reads MetaImage images only");
  if (require("NDims") != "3")
    fail(path, "NDims = " + require("NDims").substr(0, 20) + ": corrlap reads 3D volumes (NDims = 3)");
  VolumeHeader header;
  {
    const std::vector<double> d = numbers(path, "DimSize", require("DimSize"), 3);
    for (int a = 0; a < 3; ++a) {
      if (!(d[std::size_t(a)] >= 1 && d[std::size_t(a)] <= 1e9 && d[std::size_t(a)] == std::floor(d[std::size_t(a)])))
        fail(path, "DimSize = '" + require("DimSize").substr(0, 60) + "': sizes must be positive integers");
      header.size[a] = int(d[std::size_t(a)]);
    }
  }
  const std::size_t n = checked_voxels(path, header.size);
  {
    const std::string& type = require("ElementType");
    const auto* e = std::find_if(std::begin(kElementTypes), std::end(kElementTypes),
                                 [&](const ElementTypeName& t) { return type == t.name; });
    if (e == std::end(kElementTypes))
      fail(path,
           "unsupported ElementType '" + type.substr(0, 40) +
               "' (supported: MET_UCHAR, MET_CHAR, MET_SHORT, MET_USHORT, MET_INT, MET_UINT, MET_LONG, MET_ULONG, "
               "MET_LONG_LONG, MET_ULONG_LONG, MET_FLOAT, MET_DOUBLE)");
    header.type = e->type;
  }
  if (auto c = find({"ElementNumberOfChannels"}); c && c->second != "1")
    fail(path, "ElementNumberOfChannels = " + c->second.substr(0, 20) + ": corrlap reads one value per voxel");
  if (auto b = find({"BinaryData"}); b && !boolean(path, b->first, b->second))
    fail(path, "BinaryData = False (values as text) is not supported; write the image with binary data");
  if (auto msb = find({"BinaryDataByteOrderMSB", "ElementByteOrderMSB"}))
    header.big_endian = boolean(path, msb->first, msb->second);
  // Geometry.
  header.geometry.space = PhysicalSpace::LPS;
  if (auto s = find({"ElementSpacing"})) {
    const auto v = numbers(path, s->first, s->second, 3);
    header.geometry.spacing = Eigen::Vector3d(v[0], v[1], v[2]);
  } else if (auto e = find({"ElementSize"})) {
    const auto v = numbers(path, e->first, e->second, 3);
    header.geometry.spacing = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if ((header.geometry.spacing.array() <= 0.0).any())
    fail(path, "ElementSpacing must be positive, got " + readable_number(header.geometry.spacing.x()) + " " +
                   readable_number(header.geometry.spacing.y()) + " " + readable_number(header.geometry.spacing.z()));
  if (auto o = find({"Offset", "Position", "Origin"})) {
    const auto v = numbers(path, o->first, o->second, 3);
    header.geometry.origin = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if (auto m = find({"TransformMatrix", "Rotation", "Orientation"})) {
    const auto v = numbers(path, m->first, m->second, 9);
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d axis(v[std::size_t(3 * a)], v[std::size_t(3 * a + 1)], v[std::size_t(3 * a + 2)]);
      if (!(axis.norm() > 0.0)) fail(path, m->first + ": the direction of axis " + std::to_string(a) + " is zero");
      header.geometry.direction.col(a) = axis.normalized();
    }
  }
  const bool compressed = [&] {
    auto c = find({"CompressedData"});
    return c && boolean(path, c->first, c->second);
  }();
  std::int64_t header_size = 0;
  if (auto h = find({"HeaderSize"})) {
    const auto v = checked_integer(numbers(path, h->first, h->second, 1)[0], -1, std::int64_t{1} << 50);
    if (!v) fail(path, "HeaderSize = " + h->second.substr(0, 20) + ": expected -1 or a byte count");
    header_size = *v;
  }
  std::optional<std::uint64_t> compressed_size;
  if (auto c = find({"CompressedDataSize"})) {
    const auto v = checked_integer(numbers(path, c->first, c->second, 1)[0], 1, std::int64_t{1} << 50);
    if (!v) fail(path, "CompressedDataSize = " + c->second.substr(0, 20) + ": expected a positive byte count");
    compressed_size = std::uint64_t(*v);
  }
  const std::size_t bytes = n * value_bytes(header.type);

  // The values: after the header (LOCAL) or in the data file named relative to the header.
  std::ifstream external;
  std::istream* data = &in;
  std::string data_path = path;
  if (data_file == "LOCAL") {
    if (header_size != 0) fail(path, "HeaderSize with LOCAL data is not supported (the values follow the header)");
  } else {
    if (lower(data_file).rfind("list", 0) == 0 || data_file.find('%') != std::string::npos)
      fail(path, "ElementDataFile = " + data_file.substr(0, 60) +
                     ": one data file per slice (LIST or a pattern) is not supported; one file or LOCAL");
    const std::filesystem::path p(data_file);
    data_path = (p.is_absolute() ? p : std::filesystem::path(path).parent_path() / p).string();
    external.open(data_path, std::ios::binary);
    if (!external) fail(path, "cannot open its data file '" + data_path + "' (ElementDataFile = " + data_file + ")");
    // A device or a pipe has no length to check the sizes against, and may never end.
    if (!std::filesystem::is_regular_file(data_path))
      fail(path, "its data file '" + data_path + "' is not a regular file");
    data = &external;
    if (header_size == -1) {
      // The values are the last bytes of the file (MetaIO's convention for an unknown header).
      if (compressed) fail(path, "HeaderSize = -1 needs uncompressed data");
      const std::uint64_t total = bytes_left(external);
      check_holds(data_path, header.size, bytes, total);
      external.seekg(std::streamoff(total - bytes));
    } else if (header_size > 0) {
      if (std::uint64_t(header_size) > bytes_left(external))
        fail(data_path, "HeaderSize = " + std::to_string(header_size) + " is past the end of the data file");
      external.seekg(std::streamoff(header_size));
    }
  }
  if (compressed) {
    if (compressed_size && *compressed_size != bytes_left(*data))
      fail(data_path, "CompressedDataSize = " + readable_count(*compressed_size) + " but the file holds " +
                          readable_count(bytes_left(*data)) + " bytes of compressed data");
    return read_compressed_payload(*data, data_path, header, sink, "zlib");
  }
  if (bytes_left(*data) > bytes)
    fail(data_path, "the data holds " + readable_count(bytes_left(*data)) + " bytes, more than the " +
                        readable_count(bytes) + " of " + describe_sizes(header.size) + " of " +
                        value_type_name(header.type) + " (wrong DimSize or ElementType?)");
  read_payload(*data, data_path, header, sink);
}

namespace {

// ITK's three letters for the voxel axes of an LPS direction ("RAI" for the identity): per axis, the
// side its nearest anatomical axis comes from. None when two voxel axes share one anatomical axis.
std::optional<std::string> anatomical_orientation(const Eigen::Matrix3d& direction) {
  static const char from[3][2] = {{'R', 'L'}, {'A', 'P'}, {'I', 'S'}};
  std::string code;
  for (int a = 0; a < 3; ++a) {
    Eigen::Index nearest = 0;
    direction.col(a).cwiseAbs().maxCoeff(&nearest);
    const char letter = from[nearest][direction(nearest, a) > 0.0 ? 0 : 1];
    for (char used : code)
      if (used == from[nearest][0] || used == from[nearest][1]) return std::nullopt;
    code += letter;
  }
  return code;
}

}  // namespace

void write_metaimage(const std::string& path, const VolumeData& volume) {
  const bool detached = file_extension(path) == "mhd";
  // .mha: one file, zlib-compressed when built with zlib (label maps shrink a hundredfold);
  // .mhd: the values raw in a .raw file beside it, readable by any tool that takes raw data.
  const bool compressed = !detached && have_zlib();
  // ITK's world is LPS: a geometry in another anatomical space is flipped into it; one in an unknown
  // space is written as it is (and read back as LPS).
  const VolumeGeometry g =
      volume.geometry.space == PhysicalSpace::Unknown ? volume.geometry : volume.geometry.in_space(PhysicalSpace::LPS);
  if (!g.spacing.allFinite() || !g.origin.allFinite() || !g.direction.allFinite() || (g.spacing.array() <= 0).any())
    fail(path, "the geometry has a spacing that is not positive or a value that is not finite");
  const char* type = "MET_UCHAR";  // bool: its values 0 and 1 as bytes
  for (const auto& t : kElementTypes)
    if (t.type == volume.type && std::string(t.name) != "MET_LONG" && std::string(t.name) != "MET_ULONG") {
      type = t.name;
      break;
    }
  const std::filesystem::path raw_path = std::filesystem::path(path).replace_extension(".raw");
  std::ostringstream h;
  h.precision(17);
  h << "ObjectType = Image\nNDims = 3\nBinaryData = True\n";
  h << "BinaryDataByteOrderMSB = " << (std::endian::native == std::endian::big ? "True" : "False") << "\n";
  h << "CompressedData = " << (compressed ? "True" : "False") << "\n";
  // MetaIO needs the compressed length to read LOCAL data; it is known once the values are written,
  // so the field is written zero-padded and filled in then.
  std::size_t size_field = 0;
  if (compressed) {
    h << "CompressedDataSize = ";
    size_field = std::size_t(h.tellp());
    h << std::string(20, '0') << "\n";
  }
  h << "TransformMatrix =";
  for (int a = 0; a < 3; ++a)
    for (int r = 0; r < 3; ++r) h << ' ' << g.direction(r, a);
  h << "\nOffset = " << g.origin.x() << ' ' << g.origin.y() << ' ' << g.origin.z() << "\n";
  if (g.space != PhysicalSpace::Unknown) {
    if (const auto code = anatomical_orientation(g.direction)) h << "AnatomicalOrientation = " << *code << "\n";
  }
  h << "ElementSpacing = " << g.spacing.x() << ' ' << g.spacing.y() << ' ' << g.spacing.z() << "\n";
  h << "DimSize = " << volume.size.x() << ' ' << volume.size.y() << ' ' << volume.size.z() << "\n";
  h << "ElementType = " << type << "\n";
  h << "ElementDataFile = " << (detached ? raw_path.filename().string() : std::string("LOCAL")) << "\n";
  const std::string text = h.str();

  auto write_values = [&](OutputFile& out) -> std::uint64_t {
    PayloadWriter writer(out.get(), path, compressed ? PayloadWriter::Encoding::Zlib : PayloadWriter::Encoding::Raw);
    for (std::size_t done = 0; done < volume.bytes.size();) {
      const std::size_t k = std::min(kChunk, volume.bytes.size() - done);
      writer.write(volume.bytes.data() + done, k);
      done += k;
    }
    writer.finish();
    return writer.written();
  };
  if (detached) {
    // The data first: a header never names a data file that is not there.
    OutputFile raw(raw_path.string(), "volume", true);
    (void)write_values(raw);
    raw.commit();
    OutputFile out(path, "volume", false);
    std::fputs(text.c_str(), out.get());
    out.commit();
    return;
  }
  OutputFile out(path, "volume", true);
  std::fputs(text.c_str(), out.get());
  const std::uint64_t written = write_values(out);
  if (compressed) {
    char digits[32];
    std::snprintf(digits, sizeof digits, "%020llu", static_cast<unsigned long long>(written));
    if (std::fseek(out.get(), long(size_field), SEEK_SET) != 0) fail(path, "cannot seek to fill in CompressedDataSize");
    std::fputs(digits, out.get());
  }
  out.commit();
}

}  // namespace corrlap::io_detail

// NRRD volumes (io/detail/volume_readers.hpp): http://teem.sourceforge.net/nrrd/format.html.
// "NRRD000N", "field: value" lines, a blank line, then the data (attached, .nrrd) or a data file
// named by "data file" (detached, .nhdr). Typed values, raw/ascii/gzip encodings; the geometry from
// "space directions" and "space origin" (or "spacings"), in the file's own space.
#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/inside_test.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <type_traits>
#include <vector>

namespace corrlap::io_detail {

namespace {

// NRRD's spellings of each type (the C type names and the stdint names).
std::optional<VoxelValueType> nrrd_type(const std::string& t) {
  static const std::map<std::string, VoxelValueType> types = {
      {"signed char", VoxelValueType::Int8},
      {"int8", VoxelValueType::Int8},
      {"int8_t", VoxelValueType::Int8},
      {"uchar", VoxelValueType::UInt8},
      {"unsigned char", VoxelValueType::UInt8},
      {"uint8", VoxelValueType::UInt8},
      {"uint8_t", VoxelValueType::UInt8},
      {"short", VoxelValueType::Int16},
      {"short int", VoxelValueType::Int16},
      {"signed short", VoxelValueType::Int16},
      {"signed short int", VoxelValueType::Int16},
      {"int16", VoxelValueType::Int16},
      {"int16_t", VoxelValueType::Int16},
      {"ushort", VoxelValueType::UInt16},
      {"unsigned short", VoxelValueType::UInt16},
      {"unsigned short int", VoxelValueType::UInt16},
      {"uint16", VoxelValueType::UInt16},
      {"uint16_t", VoxelValueType::UInt16},
      {"int", VoxelValueType::Int32},
      {"signed int", VoxelValueType::Int32},
      {"int32", VoxelValueType::Int32},
      {"int32_t", VoxelValueType::Int32},
      {"uint", VoxelValueType::UInt32},
      {"unsigned int", VoxelValueType::UInt32},
      {"uint32", VoxelValueType::UInt32},
      {"uint32_t", VoxelValueType::UInt32},
      {"longlong", VoxelValueType::Int64},
      {"long long", VoxelValueType::Int64},
      {"long long int", VoxelValueType::Int64},
      {"signed long long", VoxelValueType::Int64},
      {"signed long long int", VoxelValueType::Int64},
      {"int64", VoxelValueType::Int64},
      {"int64_t", VoxelValueType::Int64},
      {"ulonglong", VoxelValueType::UInt64},
      {"unsigned long long", VoxelValueType::UInt64},
      {"unsigned long long int", VoxelValueType::UInt64},
      {"uint64", VoxelValueType::UInt64},
      {"uint64_t", VoxelValueType::UInt64},
      {"float", VoxelValueType::Float32},
      {"double", VoxelValueType::Float64},
  };
  const auto it = types.find(t);
  if (it == types.end()) return std::nullopt;
  return it->second;
}

// The spaces of three dimensions NRRD names, and the anatomical space each one is (Unknown for the
// spaces without anatomy); nullopt for a name that is not a 3D space.
std::optional<PhysicalSpace> nrrd_space(const std::string& s) {
  static const std::map<std::string, PhysicalSpace> spaces = {
      {"right-anterior-superior", PhysicalSpace::RAS}, {"ras", PhysicalSpace::RAS},
      {"left-anterior-superior", PhysicalSpace::LAS},  {"las", PhysicalSpace::LAS},
      {"left-posterior-superior", PhysicalSpace::LPS}, {"lps", PhysicalSpace::LPS},
      {"scanner-xyz", PhysicalSpace::Unknown},         {"3d-right-handed", PhysicalSpace::Unknown},
      {"3d-left-handed", PhysicalSpace::Unknown}};
  const auto it = spaces.find(s);
  if (it == spaces.end()) return std::nullopt;
  return it->second;
}

// NRRD's long name of a known space (what 3D Slicer writes).
const char* nrrd_space_name(PhysicalSpace space) {
  switch (space) {
    case PhysicalSpace::RAS:
      return "right-anterior-superior";
    case PhysicalSpace::LAS:
      return "left-anterior-superior";
    case PhysicalSpace::LPS:
      return "left-posterior-superior";
    case PhysicalSpace::Unknown:
      break;
  }
  return nullptr;
}

// "(x,y,z)" (blanks allowed) -> the vector; nullopt for anything else.
std::optional<Eigen::Vector3d> parse_vector(std::string s) {
  s.erase(std::remove_if(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c); }), s.end());
  if (s.size() < 7 || s.front() != '(' || s.back() != ')') return std::nullopt;
  std::istringstream ss(s.substr(1, s.size() - 2));
  Eigen::Vector3d v;
  char c1 = 0, c2 = 0;
  if (!(ss >> v.x() >> c1 >> v.y() >> c2 >> v.z()) || c1 != ',' || c2 != ',' || !v.allFinite()) return std::nullopt;
  std::string extra;
  if (ss >> extra) return std::nullopt;
  return v;
}

// The vectors of a "space directions" value: one "(x,y,z)" or "none" per axis.
std::vector<std::string> split_vectors(const std::string& value) {
  std::vector<std::string> parts;
  std::string current;
  int depth = 0;
  for (char c : value) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (depth == 0 && (c == ' ' || c == '\t')) {
      if (!current.empty()) parts.push_back(current);
      current.clear();
      if (parts.size() > 8) break;
    } else {
      current += c;
    }
  }
  if (!current.empty()) parts.push_back(current);
  return parts;
}

VolumeGeometry nrrd_geometry(const std::string& path, const std::map<std::string, std::string>& fields) {
  VolumeGeometry g;
  const auto space = fields.find("space");
  const auto space_dimension = fields.find("space dimension");
  if (space != fields.end() && space_dimension != fields.end())
    fail(path, "both 'space' and 'space dimension' are given (NRRD allows one)");
  const std::optional<PhysicalSpace> named =
      space != fields.end() ? nrrd_space(lower(space->second)) : std::optional(PhysicalSpace::Unknown);
  if (!named)
    fail(path, "space '" + space->second.substr(0, 40) +
                   "' is not a 3D space (supported: right-anterior-superior/RAS, left-anterior-superior/LAS, "
                   "left-posterior-superior/LPS, scanner-xyz, 3D-right-handed, 3D-left-handed)");
  if (space_dimension != fields.end() && space_dimension->second != "3")
    fail(path, "space dimension " + space_dimension->second.substr(0, 20) + ": corrlap reads 3D volumes (3)");
  g.space = *named;
  const bool has_space = space != fields.end() || space_dimension != fields.end();
  const auto directions = fields.find("space directions");
  const auto spacings = fields.find("spacings");
  const auto origin = fields.find("space origin");
  if ((directions != fields.end() || origin != fields.end()) && !has_space)
    fail(path, "'space directions' or 'space origin' without a 'space' or 'space dimension' field");
  if (directions != fields.end()) {
    if (spacings != fields.end()) fail(path, "both 'space directions' and 'spacings' are given (NRRD allows one)");
    const auto parts = split_vectors(directions->second);
    if (parts.size() != 3)
      fail(path, "'space directions' needs 3 vectors, got '" + directions->second.substr(0, 80) + "'");
    for (int a = 0; a < 3; ++a) {
      if (lower(parts[std::size_t(a)]) == "none")
        fail(path, "'space directions' of axis " + std::to_string(a) + " is none: all 3 axes must be spatial");
      const auto v = parse_vector(parts[std::size_t(a)]);
      if (!v)
        fail(path,
             "malformed 'space directions' vector '" + parts[std::size_t(a)].substr(0, 60) + "' (expected (x,y,z))");
      if (!(v->norm() > 0.0)) fail(path, "'space directions' of axis " + std::to_string(a) + " is the zero vector");
      g.spacing[a] = v->norm();
      g.direction.col(a) = *v / v->norm();
    }
  } else if (spacings != fields.end()) {
    std::istringstream ss(spacings->second);
    std::string token;
    for (int a = 0; a < 3; ++a) {
      double d = 0;
      if (!(ss >> token)) fail(path, "'spacings' needs 3 values, got '" + spacings->second.substr(0, 60) + "'");
      const auto r = std::from_chars(token.data(), token.data() + token.size(), d);
      if (r.ec != std::errc() || r.ptr != token.data() + token.size() || !std::isfinite(d) || d == 0.0)
        fail(path, "'spacings' value '" + token.substr(0, 30) + "' of axis " + std::to_string(a) +
                       " is not a voxel size (finite and nonzero)");
      g.spacing[a] = std::abs(d);
      if (d < 0) g.direction(a, a) = -1.0;
    }
    if (ss >> token) fail(path, "'spacings' has more than 3 values");
  }
  if (origin != fields.end()) {
    const auto v = parse_vector(origin->second);
    if (!v) fail(path, "malformed 'space origin' '" + origin->second.substr(0, 60) + "' (expected (x,y,z))");
    g.origin = *v;
  }
  return g;
}

// Reads `n` ascii values of the header's type (native byte order) into the sink.
void read_ascii(std::istream& in, const std::string& path, const VolumeHeader& header, const std::string& type_name,
                VoxelSink& sink) {
  const std::size_t n = checked_voxels(path, header.size);
  // n values need at least n digits and n - 1 separators.
  sink.check(path, header);
  check_holds(path, header.size, 2 * std::uint64_t(n) - 1, bytes_left(in), "at least ");
  sink.begin(path, header);
  visit_value_type(header.type, [&](auto t) {
    using T = decltype(t);
    if constexpr (std::is_same_v<T, bool>) {
      fail(path, "ascii data of type bool");  // no NRRD type maps to bool
    } else {
      std::vector<T> buffer;
      buffer.reserve(std::min(n, kChunk / sizeof(T)));
      std::string token;
      for (std::size_t i = 0; i < n; ++i) {
        if (!(in >> token) || token.size() > 64)
          fail(path, "truncated or malformed ascii data at value " + std::to_string(i));
        T v{};
        const auto r = std::from_chars(token.data(), token.data() + token.size(), v);
        if (r.ec == std::errc::result_out_of_range)
          fail(path, "ascii value " + token + " out of range for " + type_name);
        if (r.ec != std::errc() || r.ptr != token.data() + token.size())
          fail(path, "malformed ascii data at value " + std::to_string(i) + " ('" + token + "')");
        buffer.push_back(v);
        if (buffer.size() * sizeof(T) >= kChunk || i + 1 == n) {
          sink.consume(reinterpret_cast<const std::uint8_t*>(buffer.data()), buffer.size() * sizeof(T));
          buffer.clear();
        }
      }
    }
  });
  std::string extra;
  if (in >> extra) fail(path, "more ascii values than the announced sizes");
}

// A "line skip" or "byte skip" count.
std::int64_t skip_count(const std::string& path, const std::map<std::string, std::string>& fields, const char* key,
                        std::int64_t lowest) {
  const auto it = fields.find(key);
  if (it == fields.end()) return 0;
  std::int64_t v = 0;
  const auto& s = it->second;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || v < lowest || v > (std::int64_t{1} << 50))
    fail(path, std::string("'") + key + ": " + s.substr(0, 20) + "' is not a valid count");
  return v;
}

}  // namespace

void read_nrrd(const std::string& path, VoxelSink& sink) {
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
    std::string key = lower(trim(line.substr(0, colon)));
    if (key == "datafile") key = "data file";
    if (key == "lineskip") key = "line skip";
    if (key == "byteskip") key = "byte skip";
    fields[key] = trim(line.substr(colon + 2));
  }
  const bool detached = fields.count("data file") > 0;
  auto field = [&](const char* key) -> std::string {
    auto it = fields.find(key);
    if (it == fields.end()) fail(path, std::string("header has no '") + key + "' field");
    return it->second;
  };
  const std::string type = lower(field("type"));
  VolumeHeader header;
  if (const auto t = nrrd_type(type))
    header.type = *t;
  else
    fail(path, "unsupported type '" + type.substr(0, 40) +
                   "' (supported: int8, uint8, int16, uint16, int32, uint32, int64, uint64, float, double and their C "
                   "names)");
  const std::string dim = field("dimension");
  if (dim != "3") fail(path, "dimension must be 3, got '" + dim.substr(0, 20) + "'");
  {
    std::istringstream ss(field("sizes"));
    long long d[3];
    std::string extra;
    if (!(ss >> d[0] >> d[1] >> d[2]) || (ss >> extra)) fail(path, "malformed 'sizes' field (expected three integers)");
    for (int a = 0; a < 3; ++a) {
      if (d[a] <= 0 || d[a] > 1000000)
        fail(path, "invalid size " + std::to_string(d[a]) + " on axis " + std::to_string(a));
      header.size[a] = int(d[a]);
    }
  }
  const std::size_t n = checked_voxels(path, header.size);
  const std::size_t bytes = n * value_bytes(header.type);
  const std::string encoding = lower(field("encoding"));
  const bool ascii = encoding == "ascii" || encoding == "text" || encoding == "txt";
  if (auto it = fields.find("endian"); it != fields.end()) {
    const std::string e = lower(it->second);
    if (e != "little" && e != "big") fail(path, "invalid endian '" + it->second.substr(0, 20) + "' (little or big)");
    header.big_endian = e == "big";
  } else if (value_bytes(header.type) > 1 && !ascii) {
    fail(path, "header has no 'endian' field, which " + value_type_name(header.type) + " data in " + encoding +
                   " encoding needs (little or big)");
  }
  header.geometry = nrrd_geometry(path, fields);
  if (!ended && !detached) fail(path, "header not terminated by a blank line (truncated file?)");

  // The data: after the header, or in the data file named relative to the header.
  std::ifstream external;
  std::istream* data = &in;
  std::string data_path = path;
  if (detached) {
    const std::string name = fields["data file"];
    if (lower(name).rfind("list", 0) == 0 || name.find('%') != std::string::npos)
      fail(path, "data file '" + name.substr(0, 60) + "': several data files (LIST or a pattern) are not supported");
    const std::filesystem::path p(name);
    data_path = (p.is_absolute() ? p : std::filesystem::path(path).parent_path() / p).string();
    external.open(data_path, std::ios::binary);
    if (!external) fail(path, "cannot open its data file '" + data_path + "' (data file: " + name + ")");
    // A device or a pipe has no length to check the sizes against, and may never end.
    if (!std::filesystem::is_regular_file(data_path))
      fail(path, "its data file '" + data_path + "' is not a regular file");
    data = &external;
  }
  for (std::int64_t i = skip_count(path, fields, "line skip", 0); i > 0; --i)
    if (!data->ignore(std::numeric_limits<std::streamsize>::max(), '\n'))
      fail(data_path, "line skip: the data has fewer lines than skipped");
  const std::int64_t byte_skip = skip_count(path, fields, "byte skip", -1);
  if (byte_skip == -1) {
    // The values are the last bytes of the data (raw only).
    if (encoding != "raw") fail(path, "'byte skip: -1' needs raw encoding");
    const std::uint64_t left = bytes_left(*data);
    check_holds(data_path, header.size, bytes, left);
    data->seekg(std::streamoff(left - bytes), std::ios::cur);
  } else if (byte_skip > 0) {
    if (std::uint64_t(byte_skip) > bytes_left(*data)) fail(data_path, "byte skip is past the end of the data");
    data->seekg(std::streamoff(byte_skip), std::ios::cur);
  }
  if (encoding == "raw") {
    if (bytes_left(*data) > bytes) fail(data_path, "file is larger than the announced sizes");
    read_payload(*data, data_path, header, sink);
  } else if (ascii) {
    header.big_endian = std::endian::native == std::endian::big;  // parsed into native values
    read_ascii(*data, data_path, header, type, sink);
  } else if (encoding == "gzip" || encoding == "gz") {
    read_compressed_payload(*data, data_path, header, sink, "gzip");
  } else {
    fail(path, "unsupported encoding '" + encoding.substr(0, 20) + "' (supported: raw, ascii, gzip)");
  }
}

void write_nrrd(const std::string& path, const VolumeData& v) {
  const bool detached = file_extension(path) == "nhdr";
  const VolumeGeometry& g = v.geometry;
  if (!g.spacing.allFinite() || !g.origin.allFinite() || !g.direction.allFinite() || (g.spacing.array() <= 0).any())
    fail(path, "the geometry has a spacing that is not positive or a value that is not finite");
  // bool: its values 0 and 1 as bytes.
  const std::string type = v.type == VoxelValueType::Bool      ? "uint8"
                           : v.type == VoxelValueType::Float32 ? "float"
                           : v.type == VoxelValueType::Float64 ? "double"
                                                               : value_type_name(v.type);
  const std::filesystem::path raw_path = std::filesystem::path(path).replace_extension(".raw");
  std::ostringstream h;
  h.precision(17);
  h << "NRRD0004\n# written by corrlap\ntype: " << type << "\ndimension: 3\n";
  // An unknown space is not named: "space dimension: 3" says the vectors are in a 3D space.
  if (const char* space = nrrd_space_name(g.space))
    h << "space: " << space << "\n";
  else
    h << "space dimension: 3\n";
  h << "sizes: " << v.size.x() << ' ' << v.size.y() << ' ' << v.size.z() << "\n";
  h << "space directions:";
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d d = g.direction.col(a) * g.spacing[a];
    h << " (" << d.x() << ',' << d.y() << ',' << d.z() << ')';
  }
  h << "\nspace origin: (" << g.origin.x() << ',' << g.origin.y() << ',' << g.origin.z() << ")\n";
  h << "kinds: domain domain domain\nencoding: raw\n";
  h << "endian: " << (std::endian::native == std::endian::big ? "big" : "little") << "\n";
  if (detached) h << "data file: " << raw_path.filename().string() << "\n";
  h << "\n";
  const std::string text = h.str();
  auto write_values = [&](OutputFile& out) {
    // A short write sets the stream's error flag, which commit() reports naming the file.
    if (!v.bytes.empty()) (void)std::fwrite(v.bytes.data(), 1, v.bytes.size(), out.get());
  };
  if (detached) {
    // The data first: a header never names a data file that is not there.
    OutputFile raw(raw_path.string(), "volume", true);
    write_values(raw);
    raw.commit();
    OutputFile out(path, "volume", false);
    std::fputs(text.c_str(), out.get());
    out.commit();
    return;
  }
  OutputFile out(path, "volume", true);
  std::fputs(text.c_str(), out.get());
  write_values(out);
  out.commit();
}

}  // namespace corrlap::io_detail

// NRRD volumes (io/detail/volume_readers.hpp).
#include <algorithm>
#include <cctype>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

namespace corrlap::io_detail {

namespace {

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
  VolumeHeader header;
  header.size = s;
  header.type = s8 ? VoxelValueType::Int8 : VoxelValueType::UInt8;
  if (encoding == "raw") {
    if (io_detail::bytes_left(in) > n) fail(path, "file is larger than the announced sizes");
    io_detail::read_payload(in, path, header, sink);
  } else if (encoding == "ascii" || encoding == "text" || encoding == "txt") {
    // n values need at least n digits and n - 1 separators.
    sink.check(path, header);
    check_holds(path, s, 2 * std::uint64_t(n) - 1, io_detail::bytes_left(in), "at least ");
    sink.begin(path, header);
    std::vector<std::uint8_t> buffer;
    buffer.reserve(std::min(n, kChunk));
    for (std::size_t i = 0; i < n; ++i) {
      long long x = 0;
      if (!(in >> x)) fail(path, "truncated or malformed ascii data at value " + std::to_string(i));
      if (x < (s8 ? -128 : 0) || x > (s8 ? 127 : 255))
        fail(path, "ascii value " + std::to_string(x) + " out of range for " + type);
      buffer.push_back(std::uint8_t(x));  // int8: its two's complement byte
      if (buffer.size() == kChunk || i + 1 == n) {
        sink.consume(buffer.data(), buffer.size());
        buffer.clear();
      }
    }
    std::string extra;
    if (in >> extra) fail(path, "more ascii values than the announced sizes");
  } else if (encoding == "gzip" || encoding == "gz") {
    io_detail::read_compressed_payload(in, path, header, sink, "gzip");
  } else {
    fail(path, "unsupported encoding '" + encoding + "' (supported: raw, ascii, gzip)");
  }
}

void write_nrrd(const std::string& path, const VolumeData& v) {
  OutputFile out(path, "volume", true);
  std::fprintf(
      out.get(),
      "NRRD0004\n# written by corrlap\ntype: uint8\ndimension: 3\nsizes: %d %d %d\nencoding: raw\nendian: little\n\n",
      v.size.x(), v.size.y(), v.size.z());
  if (v.type != VoxelValueType::UInt8) fail(path, "NRRD writing is for uint8 volumes, not " + value_type_name(v.type));
  // A short write sets the stream's error flag, which commit() reports naming the file.
  if (!v.bytes.empty()) (void)std::fwrite(v.bytes.data(), 1, v.bytes.size(), out.get());
  out.commit();
}

}  // namespace corrlap::io_detail

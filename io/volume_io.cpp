#include "volume_io.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include <corrlap/core/error.hpp>

namespace corrlap {

namespace {

// 2^34 voxels (16 GiB) is beyond any volume this tool is meant for: reject before allocating.
constexpr double kMaxVoxels = 17179869184.0;

std::string extension_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && slash > dot)) return "";
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw IoError("volume file '" + path + "': " + what);
}

void check_size(const std::string& path, const Eigen::Vector3i& s) {
  if ((s.array() <= 0).any()) fail(path, "dimensions must be positive");
  if (double(s.x()) * s.y() * s.z() > kMaxVoxels) fail(path, "dimensions are absurdly large");
}

void read_payload(std::istream& in, const std::string& path, Volume& v) {
  const std::size_t n = std::size_t(v.size.x()) * std::size_t(v.size.y()) * std::size_t(v.size.z());
  v.values.resize(n);
  in.read(reinterpret_cast<char*>(v.values.data()), std::streamsize(n));
  if (std::size_t(in.gcount()) != n) {
    std::ostringstream os;
    os << "truncated data: expected " << n << " bytes, got " << in.gcount();
    fail(path, os.str());
  }
}

// DGtal .vol: "Key: value" lines ended by a line "."; then X*Y*Z bytes.
Volume read_vol(const std::string& path) {
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
    if (*end != '\0' || d <= 0 || d > 1000000) fail(path, std::string("invalid dimension ") + keys[a] + ": '" + it->second + "'");
    s[a] = int(d);
  }
  check_size(path, s);
  Volume v;
  v.size = s;
  read_payload(in, path, v);
  return v;
}

void write_vol(const std::string& path, const Volume& v) {
  std::ofstream out(path, std::ios::binary);
  if (!out) fail(path, "cannot open for writing");
  out << "Center-X: " << v.size.x() / 2 << "\nCenter-Y: " << v.size.y() / 2 << "\nCenter-Z: " << v.size.z() / 2
      << "\nX: " << v.size.x() << "\nY: " << v.size.y() << "\nZ: " << v.size.z()
      << "\nVoxel-Size: 1\nAlpha-Color: 0\nVoxel-Endian: 0\nInt-Endian: 0123\nVersion: 2\n.\n";
  out.write(reinterpret_cast<const char*>(v.values.data()), std::streamsize(v.values.size()));
  if (!out) fail(path, "write error");
}

Volume read_raw(const std::string& path, const VolumeReadOptions& options) {
  if (!options.raw_dimensions) fail(path, "raw volumes need their dimensions (--raw-dimensions NX NY NZ)");
  check_size(path, *options.raw_dimensions);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  Volume v;
  v.size = *options.raw_dimensions;
  read_payload(in, path, v);
  if (in.peek() != std::char_traits<char>::eof()) fail(path, "file is larger than the given dimensions");
  return v;
}

void write_raw(const std::string& path, const Volume& v) {
  std::ofstream out(path, std::ios::binary);
  if (!out) fail(path, "cannot open for writing");
  out.write(reinterpret_cast<const char*>(v.values.data()), std::streamsize(v.values.size()));
  if (!out) fail(path, "write error");
}

}  // namespace

Volume read_volume(const std::string& path, const VolumeReadOptions& options) {
  const std::string ext = extension_of(path);
  if (ext == "vol") return read_vol(path);
  if (ext == "raw") return read_raw(path, options);
  fail(path, "unsupported extension '" + ext + "' (supported: .vol, .raw)");
}

void write_volume(const std::string& path, const Volume& volume) {
  const std::string ext = extension_of(path);
  if (volume.values.size() != std::size_t(volume.size.prod())) fail(path, "volume data does not match its size");
  if (ext == "vol") return write_vol(path, volume);
  if (ext == "raw") return write_raw(path, volume);
  fail(path, "unsupported extension '" + ext + "' for writing (supported: .vol, .raw)");
}

VoxelGrid threshold_volume(const Volume& volume, double threshold, double h) {
  const Eigen::Vector3i s = volume.size;
  VoxelGrid grid(Eigen::Vector3i::Constant(-1), s, h);
  std::size_t inside = 0;
  for (int z = 0; z < s.z(); ++z)
    for (int y = 0; y < s.y(); ++y)
      for (int x = 0; x < s.x(); ++x)
        if (double(volume.at(x, y, z)) > threshold) {
          grid.set(x, y, z, true);
          ++inside;
        }
  if (inside == 0) throw InputError("volume: no voxel above the threshold " + std::to_string(threshold) + " (empty volume)");
  return grid;
}

VoxelGrid read_volume_as_voxels(const std::string& path, const VolumeReadOptions& options) {
  return threshold_volume(read_volume(path, options), options.threshold, options.h);
}

Volume voxels_to_volume(const VoxelGrid& grid) {
  Volume v;
  v.size = grid.size();
  v.values.assign(std::size_t(v.size.prod()), 0);
  const Eigen::Vector3i lo = grid.lower();
  for (int z = 0; z < v.size.z(); ++z)
    for (int y = 0; y < v.size.y(); ++y)
      for (int x = 0; x < v.size.x(); ++x)
        if (grid.get(x + lo.x(), y + lo.y(), z + lo.z()))
          v.values[(std::size_t(z) * v.size.y() + y) * v.size.x() + x] = 255;
  return v;
}

}  // namespace corrlap

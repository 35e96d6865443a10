// binvox volumes (io/detail/volume_readers.hpp).
// The binvox format (Patrick Min's voxelizer, ShapeNet's voxel grids): the text header
// "#binvox 1", "dim D W H", optional "translate tx ty tz" and "scale s", "data", then the voxels
// run-length encoded as (value, count) byte pairs, count 1..255. The voxel (x, y, z) is number
// x * W * H + z * W + y: y fastest, then z, then x. Voxel (x, y, z) has its centre at
// translate + scale * ((x, y, z) + 0.5) / D in the coordinates of the mesh it was voxelized from.
// Version 2 (binvox_merge) allows values 1..255 for set voxels; version 1 only 0 and 1.
#include <cmath>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/inside_test.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

namespace corrlap::io_detail {

namespace {

// The header's lines are short; a longer one is not a binvox file.
constexpr std::size_t kMaxHeaderLine = 256;

std::string next_line(std::istream& in, const std::string& path) {
  std::string line;
  char c = 0;
  while (in.get(c) && c != '\n') {
    if (line.size() >= kMaxHeaderLine) fail(path, "binvox header line longer than 256 characters (not a binvox file?)");
    line += c;
  }
  if (!in && line.empty()) fail(path, "truncated binvox header (no 'data' line)");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

double finite_number(std::istringstream& ss, const std::string& path, const std::string& field) {
  double v = 0;
  if (!(ss >> v) || !std::isfinite(v)) fail(path, "malformed binvox '" + field + "' line (expected finite numbers)");
  return v;
}

}  // namespace

void read_binvox(const std::string& path, VoxelSink& sink) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  const std::string magic = next_line(in, path);
  int version = 0;
  if (magic == "#binvox 1")
    version = 1;
  else if (magic == "#binvox 2")
    version = 2;
  else if (magic.rfind("#binvox", 0) == 0)
    fail(path, "unsupported binvox version '" + magic.substr(0, 40) + "' (supported: #binvox 1, #binvox 2)");
  else
    fail(path, "not a binvox file (missing the '#binvox 1' line)");
  long long dim[3] = {0, 0, 0};
  bool have_dim = false;
  Eigen::Vector3d translate = Eigen::Vector3d::Zero();
  double scale = 1.0;
  for (int lines = 0;; ++lines) {
    if (lines > 16) fail(path, "binvox header has more than 16 lines (missing the 'data' line?)");
    const std::string line = next_line(in, path);
    std::istringstream ss(line);
    std::string key, extra;
    ss >> key;
    if (key == "data") break;
    if (key == "dim") {
      if (!(ss >> dim[0] >> dim[1] >> dim[2])) fail(path, "malformed binvox 'dim' line (expected three integers)");
      have_dim = true;
    } else if (key == "translate") {
      for (int a = 0; a < 3; ++a) translate[a] = finite_number(ss, path, key);
    } else if (key == "scale") {
      scale = finite_number(ss, path, key);
      if (!(scale > 0)) fail(path, "binvox 'scale' must be positive, got " + readable_number(scale));
    } else {
      fail(path, "unknown binvox header line '" + line.substr(0, 60) + "' (expected dim, translate, scale, data)");
    }
    if (ss >> extra) fail(path, "binvox '" + key + "' line has extra text '" + extra.substr(0, 20) + "'");
  }
  if (!have_dim) fail(path, "binvox header has no 'dim' line");
  for (long long d : dim)
    if (d <= 0 || d > 1'000'000)
      fail(path, "binvox dim " + std::to_string(dim[0]) + " " + std::to_string(dim[1]) + " " + std::to_string(dim[2]) +
                     ": each must be 1 to 1 000 000");
  // The format defines the voxel order for cubes; readers disagree on which dim is which otherwise.
  if (dim[0] != dim[1] || dim[1] != dim[2])
    fail(path, "binvox dim " + std::to_string(dim[0]) + " " + std::to_string(dim[1]) + " " + std::to_string(dim[2]) +
                   ": binvox grids are cubes (the three dimensions must be equal)");
  VolumeHeader header;
  header.size = Eigen::Vector3i(int(dim[0]), int(dim[1]), int(dim[2]));
  header.order = {1, 2, 0};
  header.type = VoxelValueType::UInt8;
  const double step = scale / double(dim[0]);
  header.geometry.spacing = Eigen::Vector3d::Constant(step);
  header.geometry.origin = translate + Eigen::Vector3d::Constant(0.5 * step);
  const std::uint64_t n = checked_voxels(path, header.size);
  // Each pair covers at most 255 voxels: the file must hold at least n / 255 pairs.
  sink.check(path, header);
  check_holds(path, header.size, 2 * ((n + 254) / 255), bytes_left(in), "at least ");
  sink.begin(path, header);
  std::vector<std::uint8_t> pairs(2 * 4096), values;
  values.reserve(kChunk);
  std::uint64_t done = 0;
  while (done < n) {
    in.read(reinterpret_cast<char*>(pairs.data()), std::streamsize(pairs.size()));
    const std::size_t got = std::size_t(in.gcount());
    if (got < 2) fail(path, "truncated binvox data: " + readable_count(done) + " of " + readable_count(n) + " voxels");
    for (std::size_t p = 0; p + 1 < got; p += 2) {
      const std::uint8_t value = pairs[p], count = pairs[p + 1];
      if (count == 0) fail(path, "binvox run of length 0 at voxel " + readable_count(done));
      if (version == 1 && value > 1)
        fail(path, "binvox value " + std::to_string(value) + " at voxel " + readable_count(done) +
                       " in a version 1 file (values are 0 or 1)");
      if (done + count > n)
        fail(path, "binvox runs hold more voxels than dim " + std::to_string(dim[0]) + "^3 = " + readable_count(n) +
                       " (the run at voxel " + readable_count(done) + " has " + std::to_string(count) + ")");
      for (int c = 0; c < count; ++c) values.push_back(value);
      done += count;
      if (values.size() + 255 > kChunk || done == n) {
        sink.consume(values.data(), values.size());
        values.clear();
      }
      if (done == n && (p + 2 < got || in.peek() != std::char_traits<char>::eof()))
        fail(path, "binvox data goes on after the last of the " + readable_count(n) + " voxels");
    }
    if (got % 2 != 0) fail(path, "binvox data ends inside a (value, count) pair");
  }
}

void write_binvox(const std::string& path, const VolumeData& volume) {
  const Eigen::Vector3i s = volume.size;
  if (s.x() != s.y() || s.y() != s.z())
    fail(path, "binvox grids are cubes; the volume has " + describe_sizes(s) + " (pad it to a cube)");
  const VolumeGeometry& g = volume.geometry;
  if (!g.isotropic() || !g.direction.isApprox(Eigen::Matrix3d::Identity(), 0.0))
    fail(path,
         "binvox stores a uniform scale and a translation only; the volume's geometry has anisotropic spacing or "
         "rotated axes (write .nrrd or .nii to keep it)");
  const double scale = g.spacing.x() * double(s.x());
  const Eigen::Vector3d translate = g.origin - Eigen::Vector3d::Constant(0.5 * g.spacing.x());
  for (double v : {scale, translate.x(), translate.y(), translate.z()})
    if (!std::isfinite(v)) fail(path, "binvox geometry is not finite (translate or scale)");
  OutputFile out(path, "binvox", true);
  std::fprintf(out.get(), "#binvox 1\ndim %d %d %d\ntranslate %.17g %.17g %.17g\nscale %.17g\ndata\n", s.x(), s.y(),
               s.z(), translate.x(), translate.y(), translate.z(), scale);
  const std::size_t size = value_bytes(volume.type);
  auto is_set = [&](std::size_t linear) {
    return visit_value_type(volume.type, [&](auto t) {
      using T = decltype(t);
      const T v = read_value<T, false>(volume.bytes.data() + linear * size);
      if (InsideTest<T>::is_nan(v))
        fail(path, "value " + std::to_string(linear) + " is NaN (binvox values are 0 or 1)");
      return v != T(0);
    });
  };
  std::vector<std::uint8_t> pairs;
  pairs.reserve(kChunk);
  int value = -1, count = 0;
  auto flush = [&] {
    if (count == 0) return;
    pairs.push_back(std::uint8_t(value));
    pairs.push_back(std::uint8_t(count));
    if (pairs.size() >= kChunk) {
      // A short write sets the stream's error flag, which commit() reports naming the file.
      (void)std::fwrite(pairs.data(), 1, pairs.size(), out.get());
      pairs.clear();
    }
  };
  const std::size_t nx = std::size_t(s.x()), ny = std::size_t(s.y()), nz = std::size_t(s.z());
  for (std::size_t x = 0; x < nx; ++x)
    for (std::size_t z = 0; z < nz; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const int v = is_set((z * ny + y) * nx + x) ? 1 : 0;
        if (v != value || count == 255) {
          flush();
          value = v;
          count = 0;
        }
        ++count;
      }
  flush();
  if (!pairs.empty()) (void)std::fwrite(pairs.data(), 1, pairs.size(), out.get());
  out.commit();
}

}  // namespace corrlap::io_detail

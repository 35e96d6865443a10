// NIfTI, MetaImage and NRRD (io/nifti.cpp, io/metaimage.cpp, io/nrrd.cpp): typed round trips with
// their geometry, files written by other programs (nibabel, VTK; hand-written NRRD headers) read
// with their values and voxel-to-physical map, and bad inputs refused with named errors.
#include <doctest/doctest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <bit>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/inside_test.hpp>
#include <corrlap/io/volume_io.hpp>
#include <cstring>
#include <fstream>
#include <sstream>

#include "test_support.hpp"

using namespace corrlap;
using corrlap::test::read_text;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {

// A scratch name unique to this process (ctest runs test cases in parallel).
std::string scratch(const std::string& name) { return tmp_path("medical_" + std::to_string(::getpid()) + "_" + name); }

// A rotated, anisotropic map with a left-handed flip, as scans have.
VolumeGeometry scan_geometry() {
  VolumeGeometry g;
  g.spacing = Eigen::Vector3d(0.75, 0.5, 2.5);
  g.direction = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  g.direction.col(2) *= -1.0;
  g.origin = Eigen::Vector3d(-90.25, 12.5, -40.0);
  return g;
}

// Values v(i, j, k) of every type from one integer pattern (negative ones for signed types).
VolumeData pattern_volume(VoxelValueType type, const Eigen::Vector3i& size = Eigen::Vector3i(5, 4, 3)) {
  VolumeData v;
  v.size = size;
  v.type = type;
  v.geometry = scan_geometry();
  const std::size_t bytes = value_bytes(type);
  const bool is_signed = type == VoxelValueType::Int8 || type == VoxelValueType::Int16 ||
                         type == VoxelValueType::Int32 || type == VoxelValueType::Int64 ||
                         type == VoxelValueType::Float32 || type == VoxelValueType::Float64;
  const std::size_t n = std::size_t(size.prod());
  v.bytes.resize(n * bytes);
  for (std::size_t i = 0; i < n; ++i) {
    const long long x = (long long)(i * 37 % 101) - (is_signed ? 50 : 0);
    unsigned char b[8] = {};
    switch (type) {
      case VoxelValueType::Float32: {
        const float f = float(x) + 0.25f;
        std::memcpy(b, &f, 4);
        break;
      }
      case VoxelValueType::Float64: {
        const double d = double(x) + 0.125;
        std::memcpy(b, &d, 8);
        break;
      }
      default:
        std::memcpy(b, &x, bytes);  // little-endian machine: the low bytes
    }
    std::memcpy(v.bytes.data() + i * bytes, b, bytes);
  }
  return v;
}

// The affine as float32 fields hold it (NIfTI-1's header).
Eigen::Matrix4d float_rounded(const Eigen::Matrix4d& a) { return a.cast<float>().cast<double>(); }

// Message of the IoError that read_volume_data throws on path (fails the test when none is thrown).
std::string read_error(const std::string& path) {
  try {
    (void)read_volume_data(path);
  } catch (const IoError& e) {
    return e.what();
  }
  FAIL("no IoError reading " << path);
  return {};
}

void check_error(const std::string& path, const std::string& fragment) {
  CAPTURE(path);
  const std::string what = read_error(path);
  CHECK_MESSAGE(what.find(fragment) != std::string::npos, what);
  CHECK_MESSAGE(what.find(path) != std::string::npos, what);
}

// Each (file content, a fragment of its error) written to a file with `extension` and read.
void check_errors(const std::vector<std::pair<std::string, std::string>>& cases, const std::string& extension) {
  int i = 0;
  for (const auto& [content, fragment] : cases) {
    const std::string p = scratch("bad" + std::to_string(i++) + "." + extension);
    write_text(p, content);
    check_error(p, fragment);
  }
}

std::string bytes_of(const std::string& path) { return read_text(path); }

template <class T>
void poke(std::string& bytes, std::size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

// Debian's python3 with `module`, for the cross-checks; false (and a message) when missing.
bool have_python_module(const std::string& module) {
  const std::string cmd = "/usr/bin/python3 -c 'import " + module + "' >/dev/null 2>&1";
  if (std::system(cmd.c_str()) == 0) return true;
  MESSAGE("python3 module '" << module << "' not installed (scripts/install_deps.sh): cross-check skipped");
  return false;
}

void run_python(const std::string& script) {
  const std::string file = scratch("script.py"), log = scratch("script.log");
  write_text(file, script);
  const int status = std::system(("/usr/bin/python3 " + file + " >" + log + " 2>&1").c_str());
  INFO(read_text(log));
  REQUIRE(status == 0);
}

// Numbers written by the python scripts, one per line or separated by blanks.
std::vector<double> read_numbers(const std::string& path) {
  std::ifstream in(path);
  std::vector<double> v;
  double x = 0;
  while (in >> x) v.push_back(x);
  return v;
}

std::vector<double> values_as_double(const VolumeData& v) {
  std::vector<double> out;
  io_detail::visit_value_type(v.type, [&](auto t) {
    using T = decltype(t);
    for (std::size_t i = 0; i + sizeof(T) <= v.bytes.size(); i += sizeof(T)) {
      T x;
      std::memcpy(&x, v.bytes.data() + i, sizeof(T));
      out.push_back(double(x));
    }
  });
  return out;
}

Eigen::Matrix4d affine_from(const std::vector<double>& v) {
  REQUIRE(v.size() == 16);
  Eigen::Matrix4d a;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) a(r, c) = v[std::size_t(4 * r + c)];
  return a;
}

const VoxelValueType kTypes[] = {VoxelValueType::UInt8,  VoxelValueType::Int8,   VoxelValueType::Int16,
                                 VoxelValueType::UInt16, VoxelValueType::Int32,  VoxelValueType::UInt32,
                                 VoxelValueType::Int64,  VoxelValueType::UInt64, VoxelValueType::Float32,
                                 VoxelValueType::Float64};

}  // namespace

// Each writer of a typed format and the affine it gives back: NIfTI-1 holds it in float32 fields
// (equal to the rounded one up to the norm/normalize), the text headers with 17 digits (exactly).
struct RoundTripFormat {
  const char* extension;
  bool float_affine;
};
constexpr RoundTripFormat kRoundTripFormats[] = {{"nii", true},  {"nii.gz", true}, {"mha", false},
                                                 {"mhd", false}, {"nrrd", false},  {"nhdr", false}};

TEST_CASE("NIfTI, MetaImage and NRRD round trips keep every value type and the geometry") {
  for (const RoundTripFormat& format : kRoundTripFormats) {
    for (const VoxelValueType type : kTypes) {
      CAPTURE(format.extension);
      CAPTURE(value_type_name(type));
      const VolumeData v = pattern_volume(type);
      const std::string p = scratch(std::string("round.") + format.extension);
      write_volume_data(p, v);
      const VolumeData back = read_volume_data(p);
      CHECK(back.size == v.size);
      CHECK(back.type == type);
      CHECK(back.bytes == v.bytes);
      const Eigen::Matrix4d expected = format.float_affine ? float_rounded(v.geometry.affine()) : v.geometry.affine();
      CHECK((back.geometry.affine() - expected).cwiseAbs().maxCoeff() < 1e-12);
    }
  }
  // .mhd names its data file beside it; .mha is zlib-compressed when corrlap has zlib.
  CHECK(
      read_text(scratch("round.mhd")).find("ElementDataFile = medical_" + std::to_string(::getpid()) + "_round.raw") !=
      std::string::npos);
  if (nrrd_gzip_supported()) CHECK(read_text(scratch("round.mha")).find("CompressedData = True") != std::string::npos);
  // A .nii.gz is gzip, and much smaller than the values of a label map.
  VolumeData labels = pattern_volume(VoxelValueType::Int16, Eigen::Vector3i(40, 40, 40));
  std::fill(labels.bytes.begin(), labels.bytes.end(), 0);
  labels.bytes[2 * 1000] = 3;
  write_volume_data(scratch("labels.nii.gz"), labels);
  const std::string gz = bytes_of(scratch("labels.nii.gz"));
  CHECK(std::uint8_t(gz[0]) == 0x1f);
  CHECK(gz.size() < 2000);
  CHECK(read_volume_data(scratch("labels.nii.gz")).bytes == labels.bytes);
}

TEST_CASE("NIfTI: scl_slope and scl_inter give the scaled values, thresholds and labels apply to them") {
  VolumeData v = pattern_volume(VoxelValueType::Int16, Eigen::Vector3i(4, 3, 2));
  const std::string p = scratch("scaled.nii");
  write_volume_data(p, v);
  std::string bytes = bytes_of(p);
  poke<float>(bytes, 112, 2.0f);
  poke<float>(bytes, 116, -5.0f);
  write_text(p, bytes);
  const VolumeData back = read_volume_data(p);
  CHECK(back.type == VoxelValueType::Float64);
  const std::vector<double> stored = values_as_double(v), scaled = values_as_double(back);
  REQUIRE(scaled.size() == stored.size());
  std::int64_t above = 0;
  for (std::size_t i = 0; i < stored.size(); ++i) {
    CHECK(scaled[i] == 2.0 * stored[i] - 5.0);
    above += 2.0 * stored[i] - 5.0 > 10.0;
  }
  VolumeReadOptions o;
  o.inside = InsideRule::above(10.0);
  CHECK(read_volume_as_voxels(p, o).count() == above);
  // Slope 0 means no scaling (the stored values).
  poke<float>(bytes, 112, 0.0f);
  write_text(p, bytes);
  CHECK(read_volume_data(p).bytes == v.bytes);
}

TEST_CASE("NIfTI: the qform is used without an sform, with qfac, and the voxel sizes alone without either") {
  const VolumeData v = pattern_volume(VoxelValueType::UInt8);
  const std::string p = scratch("qform.nii");
  write_volume_data(p, v);
  std::string bytes = bytes_of(p);
  poke<std::int16_t>(bytes, 254, 0);  // sform_code 0: the qform (written from the same geometry)
  write_text(p, bytes);
  const VolumeGeometry q = read_volume_data(p).geometry;
  CHECK((q.affine() - v.geometry.affine()).cwiseAbs().maxCoeff() < 1e-6);  // a float32 quaternion
  CHECK(q.direction.determinant() < 0.0);                                  // qfac = -1 kept
  poke<std::int16_t>(bytes, 252, 0);                                       // no form: pixdim only
  write_text(p, bytes);
  const VolumeGeometry s = read_volume_data(p).geometry;
  CHECK(s.direction == Eigen::Matrix3d::Identity());
  CHECK(s.origin == Eigen::Vector3d::Zero());
  CHECK(s.spacing == Eigen::Vector3d(0.75, 0.5, 2.5));
}

TEST_CASE("NIfTI bad inputs are named errors") {
  const VolumeData v = pattern_volume(VoxelValueType::Int16);
  const std::string good = scratch("good.nii");
  write_volume_data(good, v);
  const std::string bytes = bytes_of(good);
  auto variant = [&](const std::string& name, auto&& edit) {
    std::string b = bytes;
    edit(b);
    const std::string p = scratch(name);
    write_text(p, b);
    return p;
  };
  check_error(variant("truncated.nii", [](std::string& b) { b.resize(b.size() - 7); }), "truncated data");
  check_error(variant("short_header.nii", [](std::string& b) { b.resize(200); }), "truncated header");
  check_error(variant("magic.nii", [](std::string& b) { std::memcpy(b.data() + 344, "abc", 4); }), "no NIfTI-1 magic");
  check_error(variant("pair.nii", [](std::string& b) { std::memcpy(b.data() + 344, "ni1", 4); }), ".hdr/.img pair");
  check_error(variant("sizeof.nii", [](std::string& b) { poke<std::int32_t>(b, 0, 123); }),
              "not a NIfTI file (sizeof_hdr is 123");
  check_error(variant("absurd.nii",
                      [](std::string& b) {
                        for (std::size_t a = 1; a <= 3; ++a) poke<std::int16_t>(b, 40 + 2 * a, 32000);
                      }),
              "absurdly large");
  check_error(variant("negative.nii", [](std::string& b) { poke<std::int16_t>(b, 42, -4); }), "dim[1] = -4");
  check_error(variant("rgb.nii",
                      [](std::string& b) {
                        poke<std::int16_t>(b, 70, 128);
                        poke<std::int16_t>(b, 72, 24);
                      }),
              "unsupported datatype 128 (RGB24)");
  check_error(variant("complex.nii", [](std::string& b) { poke<std::int16_t>(b, 70, 32); }), "(complex64)");
  check_error(variant("unknown_type.nii", [](std::string& b) { poke<std::int16_t>(b, 70, 3); }),
              "unknown datatype code 3");
  check_error(variant("bitpix.nii", [](std::string& b) { poke<std::int16_t>(b, 72, 8); }), "bitpix 8 does not match");
  check_error(variant("time.nii",
                      [](std::string& b) {
                        poke<std::int16_t>(b, 40, 4);
                        poke<std::int16_t>(b, 48, 2);
                      }),
              "dim[4] = 2");
  check_error(variant("offset.nii", [](std::string& b) { poke<float>(b, 108, 1e6f); }), "past the end of the file");
  check_error(variant("offset_inside.nii", [](std::string& b) { poke<float>(b, 108, 100.0f); }), "vox_offset = 100");
  check_error(variant("sform.nii", [](std::string& b) { poke<float>(b, 280, std::nanf("")); }), "not finite");
  // A gzip file whose announced sizes its bytes cannot hold is refused before inflating.
  std::string hb = bytes_of(good);
  hb.resize(352);
  for (std::size_t a = 1; a <= 3; ++a) poke<std::int16_t>(hb, 40 + 2 * a, 2000);
  const std::string raw = scratch("bomb_header.nii"), gz = scratch("bomb.nii.gz");
  write_text(raw, hb);
  REQUIRE(std::system(("gzip -c " + raw + " > " + gz).c_str()) == 0);
  check_error(gz, "of gzip data can hold");
  // Wrong magic in a gzip file, truncated gzip data.
  const std::string gz_good = scratch("good.nii.gz");
  write_volume_data(gz_good, v);
  std::string gzb = bytes_of(gz_good);
  gzb.resize(gzb.size() / 2);
  write_text(scratch("cut.nii.gz"), gzb);
  const std::string cut = read_error(scratch("cut.nii.gz"));
  CHECK_MESSAGE((cut.find("truncated") != std::string::npos || cut.find("gzip") != std::string::npos), cut);
}

TEST_CASE("NIfTI files written by nibabel: NIfTI-1, NIfTI-2, gzip, big-endian, qform only") {
  if (!have_python_module("nibabel")) return;
  const std::string dir = scratch("nibabel");
  std::filesystem::create_directories(dir);
  // corrlap writes one file nibabel reads back.
  write_volume_data(dir + "/ours.nii.gz", pattern_volume(VoxelValueType::Int16));
  run_python(R"(import numpy as np, nibabel as nib, sys
d = ')" + dir +
             R"('
shape = (5, 4, 3)
base = (np.arange(60).reshape(shape, order='F') * 37 % 101 - 50)
# A rotated, anisotropic affine with a flip, and an origin in millimetres.
t = 0.4
rot = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, -1]])
aff = np.eye(4)
aff[:3, :3] = rot @ np.diag([0.7, 0.9, 2.5])
aff[:3, 3] = [-100.5, 20.25, 33.0]
def save(img, name, data):
    nib.save(img, d + '/' + name)
    back = nib.load(d + '/' + name)
    np.savetxt(d + '/' + name + '.affine', back.affine, fmt='%.17g')
    np.savetxt(d + '/' + name + '.values', np.asarray(back.get_fdata()).ravel(order='F'), fmt='%.17g')
save(nib.Nifti1Image(base.astype(np.int16), aff), 'n1.nii', base)
save(nib.Nifti2Image(base.astype(np.float32) + 0.5, aff), 'n2.nii', base)
save(nib.Nifti1Image(base.astype(np.uint8) % 7, aff), 'n1gz.nii.gz', base)
save(nib.Nifti2Image(base.astype(np.int32), aff), 'n2gz.nii.gz', base)
be = nib.Nifti1Header(endianness='>')
be.set_data_dtype('>i2')
save(nib.Nifti1Image(base.astype('>i2'), aff, be), 'big.nii', base)
q = nib.Nifti1Image(base.astype(np.uint16) + 50, aff)
q.set_sform(None, code=0)
q.set_qform(aff, code=1)
save(q, 'qform.nii', base)
ours = nib.load(d + '/ours.nii.gz')
np.savetxt(d + '/ours.affine', ours.affine, fmt='%.17g')
np.savetxt(d + '/ours.values', np.asarray(ours.dataobj).ravel(order='F'), fmt='%.17g')
print(nib.load(d + '/n2.nii').header.sizeof_hdr, nib.load(d + '/big.nii').header.endianness)
)");
  for (const char* name : {"n1.nii", "n2.nii", "n1gz.nii.gz", "n2gz.nii.gz", "big.nii", "qform.nii"}) {
    CAPTURE(name);
    const std::string p = dir + "/" + name;
    const VolumeData v = read_volume_data(p);
    CHECK(v.size == Eigen::Vector3i(5, 4, 3));
    CHECK(values_as_double(v) == read_numbers(p + ".values"));
    const Eigen::Matrix4d nib = affine_from(read_numbers(p + ".affine"));
    // The qform is a float32 quaternion: nibabel and corrlap round it differently.
    const double tolerance = std::string(name) == "qform.nii" ? 1e-6 : 1e-12;
    CHECK((v.geometry.affine() - nib).cwiseAbs().maxCoeff() < tolerance);
  }
  CHECK(read_volume_data(dir + "/big.nii").type == VoxelValueType::Int16);
  CHECK(read_volume_data(dir + "/n2.nii").type == VoxelValueType::Float32);
  // nibabel reads corrlap's file: the same values and affine.
  const VolumeData ours = pattern_volume(VoxelValueType::Int16);
  CHECK(values_as_double(ours) == read_numbers(dir + "/ours.values"));
  CHECK(
      (affine_from(read_numbers(dir + "/ours.affine")) - float_rounded(ours.geometry.affine())).cwiseAbs().maxCoeff() <
      1e-12);
}

TEST_CASE("MetaImage headers as ITK writes them: TransformMatrix triples are the axes, byte order, synonyms") {
  const std::string p = scratch("itk.mha");
  // Big-endian int16, axis i along +y, axis j along -x: ITK lists the direction of each axis in turn.
  std::string values;
  for (int i = 0; i < 8; ++i) {
    values += char(0);
    values += char(i * 10);
  }
  write_text(p,
             "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = True\n"
             "CompressedData = False\nTransformMatrix = 0 1 0 -1 0 0 0 0 1\nPosition = 1 2 3\n"
             "CenterOfRotation = 0 0 0\nAnatomicalOrientation = RAI\nElementSpacing = 0.5 2 3\n"
             "DimSize = 2 2 2\nElementType = MET_SHORT\nElementDataFile = LOCAL\n" +
                 values);
  const VolumeData v = read_volume_data(p);
  CHECK(v.type == VoxelValueType::Int16);
  CHECK(values_as_double(v) == std::vector<double>{0, 10, 20, 30, 40, 50, 60, 70});
  CHECK(v.geometry.to_physical(Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(1, 2.5, 3)));
  CHECK(v.geometry.to_physical(Eigen::Vector3d(0, 1, 0)).isApprox(Eigen::Vector3d(-1, 2, 3)));
  CHECK(v.geometry.to_physical(Eigen::Vector3d(0, 0, 1)).isApprox(Eigen::Vector3d(1, 2, 6)));
  // ElementSize stands for the spacing when ElementSpacing is absent.
  write_text(p, "NDims = 3\nDimSize = 2 2 2\nElementSize = 1 1 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" +
                    std::string(8, '\1'));
  CHECK(read_volume_data(p).geometry.spacing == Eigen::Vector3d(1, 1, 4));
  // A data file with a header of its own (HeaderSize), relative to the .mhd.
  write_text(scratch("skip.raw"), "HEADER" + std::string(8, '\2'));
  write_text(scratch("skip.mhd"),
             "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nHeaderSize = 6\n"
             "ElementDataFile = medical_" +
                 std::to_string(::getpid()) + "_skip.raw\n");
  CHECK(read_volume_data(scratch("skip.mhd")).bytes == std::vector<std::uint8_t>(8, 2));
}

TEST_CASE("MetaImage bad inputs are named errors") {
  const std::string head = "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "no ElementDataFile"},
      {"\x89PNG\r\n", "not a MetaImage header"},
      {head + "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n1234567", "truncated data"},
      {head + "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n123456789", "more than the 8"},
      {head + "ElementType = MET_STRING\nElementDataFile = LOCAL\n12345678", "unsupported ElementType 'MET_STRING'"},
      {head + "ElementDataFile = LOCAL\n12345678", "no ElementType"},
      {"NDims = 2\nDimSize = 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n1234", "NDims = 2"},
      {"NDims = 3\nDimSize = 100000 100000 100000\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n1",
       "absurdly large"},
      {"NDims = 3\nDimSize = 2 0 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "sizes must be positive"},
      {head + "ElementType = MET_UCHAR\nElementNumberOfChannels = 3\nElementDataFile = LOCAL\n",
       "ElementNumberOfChannels = 3"},
      {head + "ElementType = MET_UCHAR\nElementDataFile = missing.raw\n", "cannot open its data file"},
      {head + "ElementType = MET_UCHAR\nElementDataFile = LIST\n", "LIST or a pattern"},
      {head + "ElementType = MET_UCHAR\nElementSpacing = 1 0 1\nElementDataFile = LOCAL\n12345678", "positive"},
      {head + "ElementType = MET_UCHAR\nOffset = 1 2\nElementDataFile = LOCAL\n12345678", "expected 3 finite numbers"},
      {head + "ElementType = MET_UCHAR\nOffset = 1 2 3\nOrigin = 1 2 3\nElementDataFile = LOCAL\n12345678", "synonyms"},
      {head + "ElementType = MET_UCHAR\nCompressedData = True\nElementDataFile = LOCAL\nnot zlib", "zlib"},
      {head + "ElementType = MET_UCHAR\nBinaryDataByteOrderMSB = maybe\nElementDataFile = LOCAL\n12345678",
       "expected True or False"},
  };
  check_errors(cases, "mha");
}

TEST_CASE("MetaImage files written by VTK are read with their values and geometry, and VTK reads ours") {
  if (!have_python_module("vtk")) return;
  const std::string dir = scratch("vtk");
  std::filesystem::create_directories(dir);
  VolumeData ours = pattern_volume(VoxelValueType::Int16);
  ours.geometry.direction.setIdentity();  // VTK's MetaImage reader ignores orientation
  write_volume_data(dir + "/ours.mha", ours);
  run_python(R"(import vtk, numpy as np
from vtk.util import numpy_support
d = ')" + dir +
             R"('
img = vtk.vtkImageData()
img.SetDimensions(5, 4, 3)
img.SetSpacing(0.7, 0.9, 2.5)
img.SetOrigin(-100.5, 20.25, 33.0)
values = (np.arange(60) * 37 % 101 - 50).astype(np.int16)
img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(values, deep=1, array_type=vtk.VTK_SHORT))
for name, compress in (('vtk.mha', True), ('vtk.mhd', False)):
    w = vtk.vtkMetaImageWriter()
    w.SetFileName(d + '/' + name)
    if name.endswith('.mhd'):
        w.SetRAWFileName(d + '/vtk.raw')
    w.SetCompression(compress)
    w.SetInputData(img)
    w.Write()
np.savetxt(d + '/vtk.values', values, fmt='%d')
r = vtk.vtkMetaImageReader()
r.SetFileName(d + '/ours.mha')
r.Update()
out = r.GetOutput()
np.savetxt(d + '/ours.values', numpy_support.vtk_to_numpy(out.GetPointData().GetScalars()), fmt='%.17g')
np.savetxt(d + '/ours.geometry', list(out.GetSpacing()) + list(out.GetOrigin()), fmt='%.17g')
)");
  const std::vector<double> expected = read_numbers(dir + "/vtk.values");
  for (const char* name : {"vtk.mha", "vtk.mhd"}) {
    CAPTURE(name);
    const VolumeData v = read_volume_data(dir + "/" + name);
    CHECK(v.type == VoxelValueType::Int16);
    CHECK(v.size == Eigen::Vector3i(5, 4, 3));
    CHECK(values_as_double(v) == expected);
    CHECK((v.geometry.spacing - Eigen::Vector3d(0.7, 0.9, 2.5)).norm() < 1e-6);  // VTK writes float32 spacings
    CHECK((v.geometry.origin - Eigen::Vector3d(-100.5, 20.25, 33.0)).norm() < 1e-12);
    CHECK(v.geometry.direction == Eigen::Matrix3d::Identity());
  }
  CHECK(read_numbers(dir + "/ours.values") == values_as_double(ours));
  const std::vector<double> g = read_numbers(dir + "/ours.geometry");
  REQUIRE(g.size() == 6);
  CHECK((Eigen::Vector3d(g[0], g[1], g[2]) - ours.geometry.spacing).norm() < 1e-12);
  CHECK((Eigen::Vector3d(g[3], g[4], g[5]) - ours.geometry.origin).norm() < 1e-12);
}

TEST_CASE("NRRD headers as Slicer and teem write them: space, space directions, origin, big-endian, gzip, ascii") {
  const std::string p = scratch("slicer.nrrd");
  std::string be;
  for (int i = 0; i < 8; ++i) {
    be += char(0);
    be += char(i);
  }
  // A segmentation in LPS with a direction that swaps the first two axes.
  write_text(p,
             "NRRD0005\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 2 2 2\n"
             "space directions: (0,0.5,0) (-0.75,0,0) (0,0,2.5)\nkinds: domain domain domain\nendian: big\n"
             "encoding: raw\nspace origin: (10,-20.5,30)\nSegment0_Name:=liver\n\n" +
                 be);
  const VolumeData v = read_volume_data(p);
  CHECK(v.type == VoxelValueType::Int16);
  CHECK(values_as_double(v) == std::vector<double>{0, 1, 2, 3, 4, 5, 6, 7});
  CHECK(v.geometry.spacing.isApprox(Eigen::Vector3d(0.5, 0.75, 2.5)));
  CHECK(v.geometry.to_physical(Eigen::Vector3d(1, 1, 1)).isApprox(Eigen::Vector3d(10 - 0.75, -20.5 + 0.5, 32.5)));
  // "spacings" without space directions; float ascii values.
  write_text(p, "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 1 1\nspacings: 1 1.5 -2\nencoding: ascii\n\n0.5 -1e3\n");
  const VolumeData f = read_volume_data(p);
  CHECK(values_as_double(f) == std::vector<double>{0.5, -1000});
  CHECK(f.geometry.spacing == Eigen::Vector3d(1, 1.5, 2));
  CHECK(f.geometry.to_physical(Eigen::Vector3d(0, 0, 1)) == Eigen::Vector3d(0, 0, -2));
  // Thresholding typed values: uint16 labels above 255.
  std::string u16;
  for (int i = 0; i < 8; ++i) {
    u16 += char(i);
    u16 += char(i % 2 ? 1 : 0);  // little-endian: i + 256 for odd i
  }
  write_text(p, "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n\n" + u16);
  VolumeReadOptions o;
  o.inside = InsideRule::label(257);
  CHECK(read_volume_as_voxels(p, o).count() == 1);
}

TEST_CASE("NRRD bad inputs of the typed reader are named errors") {
  const std::string head = "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {head + "\n1234567890123456", "no 'endian' field"},
      {head + "endian: little\n\n123456789012345", "truncated data"},
      {"NRRD0004\ntype: block\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n12345678", "unsupported type 'block'"},
      {head + "endian: little\nspace: RAS\nspace directions: (1,0,0) none (0,0,1)\n\n1234567890123456",
       "all 3 axes must be spatial"},
      {head + "endian: little\nspace: RAS\nspace directions: (1,0,0) (0,1,0)\n\n1234567890123456", "needs 3 vectors"},
      {head + "endian: little\nspace: RAS\nspace directions: (1,0,0) (0,1) (0,0,1)\n\n1234567890123456",
       "malformed 'space directions' vector '(0,1)'"},
      {head + "endian: little\nspace: RAS\nspace directions: (1,0,0) (0,0,0) (0,0,1)\n\n1234567890123456",
       "zero vector"},
      {head + "endian: little\nspace: RAST\n\n1234567890123456", "is not a 3D space"},
      {head + "endian: little\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n\n1234567890123456",
       "without a 'space' or 'space dimension'"},
      {head +
           "endian: little\nspace: RAS\nspace directions: (1,0,0) (0,1,0) (0,0,1)\nspacings: 1 1 1\n\n1234567890123456",
       "both 'space directions' and 'spacings'"},
      {head + "endian: little\nspacings: 1 nan 1\n\n1234567890123456", "not a voxel size"},
      {head + "endian: little\nspace: RAS\nspace origin: (1,2)\n\n1234567890123456", "malformed 'space origin'"},
      {head + "endian: little\ndata file: missing.raw\n\n", "cannot open its data file"},
      {"NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n1 2 3 4 5 6 7 40000", "out of range"},
  };
  check_errors(cases, "nrrd");
}

TEST_CASE("NRRD and MetaImage data files must be regular files (a device has no length and may never end)") {
  const std::string nrrd = scratch("device.nhdr"), mhd = scratch("device.mhd");
  write_text(nrrd, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: gzip\ndata file: /dev/zero\n\n");
  check_error(nrrd, "is not a regular file");
  write_text(mhd, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = /dev/zero\n");
  check_error(mhd, "is not a regular file");
}

TEST_CASE("Physical spaces: NIfTI is RAS, MetaImage LPS, NRRD its 'space' field, and the writers convert") {
  // The spaces NRRD names, long and short, and those without anatomy.
  const std::pair<const char*, PhysicalSpace> nrrd_spaces[] = {
      {"right-anterior-superior", PhysicalSpace::RAS}, {"RAS", PhysicalSpace::RAS},
      {"left-anterior-superior", PhysicalSpace::LAS},  {"LAS", PhysicalSpace::LAS},
      {"left-posterior-superior", PhysicalSpace::LPS}, {"LPS", PhysicalSpace::LPS},
      {"scanner-xyz", PhysicalSpace::Unknown},         {"3D-right-handed", PhysicalSpace::Unknown},
      {"3D-left-handed", PhysicalSpace::Unknown}};
  const std::string named = scratch("named.nrrd");
  for (const auto& entry : nrrd_spaces) {
    const char* name = entry.first;  // not a structured binding: clang 14 cannot capture one in CAPTURE
    const PhysicalSpace space = entry.second;
    CAPTURE(name);
    write_text(named, std::string("NRRD0004\ntype: uint8\ndimension: 3\nspace: ") + name +
                          "\nsizes: 1 1 1\nspace directions: (1,0,0) (0,1,0) (0,0,1)\nencoding: raw\n\n\1");
    CHECK(read_volume_data(named).geometry.space == space);
  }
  write_text(named, "NRRD0004\ntype: uint8\ndimension: 3\nspace dimension: 3\nsizes: 1 1 1\nencoding: raw\n\n\1");
  CHECK(read_volume_data(named).geometry.space == PhysicalSpace::Unknown);

  // A segmentation in LPS, as 3D Slicer saves a .seg.nrrd.
  VolumeData lps = pattern_volume(VoxelValueType::UInt8);
  lps.geometry.space = PhysicalSpace::LPS;
  const Eigen::Matrix4d flip_xy = Eigen::Vector4d(-1, -1, 1, 1).asDiagonal();
  // NRRD names the space and keeps the numbers.
  write_volume_data(scratch("lps.nrrd"), lps);
  CHECK(read_text(scratch("lps.nrrd")).find("space: left-posterior-superior\n") != std::string::npos);
  const VolumeGeometry as_nrrd = read_volume_data(scratch("lps.nrrd")).geometry;
  CHECK(as_nrrd.space == PhysicalSpace::LPS);
  CHECK((as_nrrd.affine() - lps.geometry.affine()).cwiseAbs().maxCoeff() < 1e-12);
  // NIfTI is RAS: the same voxels at the same anatomy, x and y flipped.
  write_volume_data(scratch("lps.nii.gz"), lps);
  const VolumeGeometry as_nifti = read_volume_data(scratch("lps.nii.gz")).geometry;
  CHECK(as_nifti.space == PhysicalSpace::RAS);
  CHECK((as_nifti.affine() - float_rounded(flip_xy * lps.geometry.affine())).cwiseAbs().maxCoeff() < 1e-12);
  // MetaImage is LPS: a RAS geometry is flipped into it, with ITK's letters for the axes.
  VolumeData ras = lps;
  ras.geometry = lps.geometry.in_space(PhysicalSpace::RAS);
  CHECK((ras.geometry.affine() - flip_xy * lps.geometry.affine()).cwiseAbs().maxCoeff() < 1e-12);
  write_volume_data(scratch("ras.mha"), ras);
  const VolumeGeometry as_meta = read_volume_data(scratch("ras.mha")).geometry;
  CHECK(as_meta.space == PhysicalSpace::LPS);
  CHECK((as_meta.affine() - lps.geometry.affine()).cwiseAbs().maxCoeff() < 1e-12);
  VolumeData axes = lps;
  axes.geometry.direction = Eigen::Vector3d(1, -1, 1).asDiagonal();  // i to the left, j anterior, k superior
  write_volume_data(scratch("axes.mha"), axes);
  CHECK(read_text(scratch("axes.mha")).find("AnatomicalOrientation = RPI\n") != std::string::npos);
  // An unknown space is written as it is, and not named.
  write_volume_data(scratch("unknown.nrrd"), pattern_volume(VoxelValueType::UInt8));
  CHECK(read_text(scratch("unknown.nrrd")).find("space dimension: 3\n") != std::string::npos);
  CHECK(read_volume_data(scratch("unknown.nrrd")).geometry.space == PhysicalSpace::Unknown);
  write_volume_data(scratch("unknown.mha"), pattern_volume(VoxelValueType::UInt8));
  CHECK(read_text(scratch("unknown.mha")).find("AnatomicalOrientation") == std::string::npos);

  // Conversions: between known spaces by flips, refused from or to an unknown one.
  CHECK(space_change(PhysicalSpace::LPS, PhysicalSpace::RAS) ==
        Eigen::Matrix3d(Eigen::Vector3d(-1, -1, 1).asDiagonal()));
  CHECK(space_change(PhysicalSpace::LAS, PhysicalSpace::LPS) ==
        Eigen::Matrix3d(Eigen::Vector3d(1, -1, 1).asDiagonal()));
  CHECK(space_change(PhysicalSpace::Unknown, PhysicalSpace::Unknown) == Eigen::Matrix3d::Identity());
  CHECK_THROWS_WITH_AS(space_change(PhysicalSpace::Unknown, PhysicalSpace::RAS),
                       doctest::Contains("an unknown space has no anatomical axes"), InputError);
  CHECK(space_name(PhysicalSpace::LPS) == "LPS");
}

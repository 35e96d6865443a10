// numpy volumes (io/detail/volume_readers.hpp).
// The .npy format (numpy.lib.format): the magic "\x93NUMPY", a major and a minor version byte, the
// header length (2 bytes little-endian for version 1, 4 bytes for versions 2 and 3), then a Python
// dict literal {'descr': ..., 'fortran_order': ..., 'shape': ...} padded with spaces and ended by
// a newline, then the array's values.
#include <bit>
#include <cctype>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/output_file.hpp>
#include <corrlap/io/detail/volume_readers.hpp>
#include <cstdio>
#include <fstream>
#include <map>
#include <vector>

namespace corrlap::io_detail {

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicLength = 6;
// numpy itself refuses headers above 10 000 bytes unless told otherwise; a volume's header is ~128.
constexpr std::uint32_t kMaxHeaderLength = 65536;

// The dict literal of the header, parsed strictly: string keys, values that are strings, True or
// False, or a tuple of non-negative integers; nothing else.
class HeaderParser {
 public:
  HeaderParser(const std::string& path, const std::string& text) : path_(path), s_(text) {}

  struct Value {
    std::string text;  // a string or True/False
    std::vector<long long> tuple;
    bool is_tuple = false;
  };

  std::map<std::string, Value> parse() {
    std::map<std::string, Value> dict;
    skip_spaces();
    expect('{');
    skip_spaces();
    while (peek() != '}') {
      const std::string key = string_literal();
      skip_spaces();
      expect(':');
      skip_spaces();
      Value v;
      if (peek() == '\'' || peek() == '"') {
        v.text = string_literal();
      } else if (peek() == '(') {
        v.is_tuple = true;
        v.tuple = tuple();
      } else if (peek() == '[') {
        bad("a structured dtype (a list of fields) for '" + key + "'; corrlap reads one value per voxel");
      } else {
        v.text = word();
      }
      if (!dict.emplace(key, v).second) bad("the key '" + key + "' appears twice");
      skip_spaces();
      if (peek() == ',') {
        ++at_;
        skip_spaces();
      } else if (peek() != '}') {
        bad("expected ',' or '}' after the value of '" + key + "'");
      }
    }
    ++at_;
    skip_spaces();
    if (at_ != s_.size()) bad("text after the closing '}'");
    return dict;
  }

 private:
  [[noreturn]] void bad(const std::string& what) const {
    fail(path_, "malformed numpy header at byte " + std::to_string(at_) + ": " + what);
  }
  char peek() const {
    if (at_ >= s_.size()) bad("the header ends early");
    return s_[at_];
  }
  void expect(char c) {
    if (peek() != c) bad(std::string("expected '") + c + "'");
    ++at_;
  }
  void skip_spaces() {
    while (at_ < s_.size() && (s_[at_] == ' ' || s_[at_] == '\n' || s_[at_] == '\t')) ++at_;
  }
  std::string string_literal() {
    const char quote = peek();
    if (quote != '\'' && quote != '"') bad("expected a quoted key");
    const auto end = s_.find(quote, at_ + 1);
    if (end == std::string::npos) bad("unterminated string");
    std::string out = s_.substr(at_ + 1, end - at_ - 1);
    if (out.find('\\') != std::string::npos) bad("escape sequences are not expected in '" + out.substr(0, 40) + "'");
    at_ = end + 1;
    return out;
  }
  std::string word() {
    const std::size_t start = at_;
    while (at_ < s_.size() && std::isalnum(static_cast<unsigned char>(s_[at_]))) ++at_;
    if (at_ == start) bad("expected a value");
    return s_.substr(start, at_ - start);
  }
  std::vector<long long> tuple() {
    expect('(');
    std::vector<long long> out;
    skip_spaces();
    while (peek() != ')') {
      const std::size_t start = at_;
      long long v = 0;
      while (at_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[at_]))) {
        if (v > 1'000'000'000'000LL) bad("a shape entry too large");
        v = 10 * v + (s_[at_++] - '0');
      }
      if (at_ == start) bad("expected a non-negative integer in the shape");
      if (out.size() >= 32) bad("more than 32 dimensions");
      out.push_back(v);
      skip_spaces();
      if (peek() == ',') {
        ++at_;
        skip_spaces();
      } else if (peek() != ')') {
        bad("expected ',' or ')' in the shape");
      }
    }
    ++at_;
    return out;
  }

  const std::string& path_;
  const std::string& s_;
  std::size_t at_ = 0;
};

std::string shape_text(const std::vector<long long>& shape) {
  std::string out = "(";
  for (std::size_t a = 0; a < shape.size(); ++a) out += (a ? ", " : "") + std::to_string(shape[a]);
  return out + (shape.size() == 1 ? ",)" : ")");
}

// The value type and byte order of a descr such as '<i2', '|b1', '>f8'.
void parse_descr(const std::string& path, const std::string& descr, VolumeHeader& header) {
  static const std::map<std::string, VoxelValueType> types = {
      {"b1", VoxelValueType::Bool},    {"i1", VoxelValueType::Int8},    {"i2", VoxelValueType::Int16},
      {"i4", VoxelValueType::Int32},   {"i8", VoxelValueType::Int64},   {"u1", VoxelValueType::UInt8},
      {"u2", VoxelValueType::UInt16},  {"u4", VoxelValueType::UInt32},  {"u8", VoxelValueType::UInt64},
      {"f4", VoxelValueType::Float32}, {"f8", VoxelValueType::Float64},
  };
  const std::string supported =
      " (supported: bool, int8 ... int64, uint8 ... uint64, float32, float64, either byte order; convert with "
      "array.astype(...))";
  // descr may be anything the file says, even empty or one character: read it through `code`.
  const char order = descr.empty() ? '\0' : descr[0];
  const std::string code = descr.size() > 1 ? descr.substr(1) : std::string();
  const auto it = types.find(code);
  if ((order != '<' && order != '>' && order != '|') || it == types.end()) {
    const char kind = descr.size() > 1 ? descr[1] : '\0';
    std::string what = "unsupported dtype '" + descr.substr(0, 40) + "'";
    if (kind == 'c') what = "complex dtype '" + descr + "' is not supported";
    if (kind == 'O') what = "object dtype '" + descr + "' is not supported (a numpy array of Python objects)";
    if (kind == 'U' || kind == 'S' || kind == 'a') what = "string dtype '" + descr.substr(0, 40) + "' is not supported";
    if (kind == 'V') what = "void (structured) dtype '" + descr.substr(0, 40) + "' is not supported";
    if (code == "f2") what = "float16 dtype '" + descr + "' is not supported";
    if (kind == 'M' || kind == 'm') what = "datetime dtype '" + descr.substr(0, 40) + "' is not supported";
    fail(path, what + supported, "dtype");
  }
  header.type = it->second;
  if (order == '|' && value_bytes(header.type) > 1)
    fail(path, "dtype '" + descr + "' has no byte order ('|') but " + std::to_string(value_bytes(header.type)) +
                   "-byte values need '<' or '>'");
  header.big_endian = order == '>';
}

}  // namespace

void read_npy(const std::string& path, VoxelSink& sink) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  char start[kMagicLength + 2] = {};
  in.read(start, sizeof start);
  if (std::size_t(in.gcount()) < kMagicLength || std::string(start, kMagicLength) != std::string(kMagic, kMagicLength))
    fail(path, "not a numpy file (missing the \\x93NUMPY magic)");
  if (in.gcount() != sizeof start) fail(path, "truncated numpy header (no version)");
  const int major = static_cast<unsigned char>(start[kMagicLength]);
  if (major < 1 || major > 3)
    fail(path, "unsupported numpy format version " + std::to_string(major) + "." +
                   std::to_string(static_cast<unsigned char>(start[kMagicLength + 1])) + " (supported: 1.0, 2.0, 3.0)");
  unsigned char length_bytes[4] = {};
  const std::streamsize length_size = major == 1 ? 2 : 4;
  in.read(reinterpret_cast<char*>(length_bytes), length_size);
  if (in.gcount() != length_size) fail(path, "truncated numpy header (no header length)");
  const std::uint32_t length = std::uint32_t(length_bytes[0]) | std::uint32_t(length_bytes[1]) << 8 |
                               std::uint32_t(length_bytes[2]) << 16 | std::uint32_t(length_bytes[3]) << 24;
  if (length > kMaxHeaderLength)
    fail(path, "numpy header length " + std::to_string(length) + " is above " + std::to_string(kMaxHeaderLength) +
                   " bytes (a corrupt file?)");
  if (length > bytes_left(in))
    fail(path, "truncated numpy header: " + std::to_string(length) + " bytes announced, " +
                   std::to_string(bytes_left(in)) + " in the file");
  std::string text(length, '\0');
  in.read(text.data(), std::streamsize(length));
  if (text.empty() || text.back() != '\n') fail(path, "malformed numpy header: it does not end with a newline");
  text.pop_back();
  const auto dict = HeaderParser(path, text).parse();
  for (const auto& [key, value] : dict)
    if (key != "descr" && key != "fortran_order" && key != "shape")
      fail(path, "malformed numpy header: unexpected key '" + key.substr(0, 40) + "'");
  auto field = [&](const char* key) -> const HeaderParser::Value& {
    const auto it = dict.find(key);
    if (it == dict.end()) fail(path, std::string("malformed numpy header: no '") + key + "' key");
    return it->second;
  };
  const auto& descr = field("descr");
  const auto& fortran = field("fortran_order");
  const auto& shape = field("shape");
  if (descr.is_tuple) fail(path, "malformed numpy header: 'descr' is not a string");
  if (fortran.is_tuple || (fortran.text != "True" && fortran.text != "False"))
    fail(path, "malformed numpy header: 'fortran_order' is not True or False");
  if (!shape.is_tuple) fail(path, "malformed numpy header: 'shape' is not a tuple");

  VolumeHeader header;
  parse_descr(path, descr.text, header);
  // A trailing axis of length 1 (one channel, channels last) is the same voxels as the 3-D array.
  std::vector<long long> dims = shape.tuple;
  if (dims.size() == 4 && dims[3] == 1) dims.pop_back();
  if (dims.size() != 3)
    fail(path,
         "the array has shape " + shape_text(shape.tuple) + ": a volume is a 3-D array (" +
             (shape.tuple.size() == 2 ? "add an axis: array[:, :, None]" : "one value per voxel") + ")",
         "shape");
  for (int a = 0; a < 3; ++a) {
    if (dims[std::size_t(a)] <= 0 || dims[std::size_t(a)] > 2'000'000'000LL)
      fail(path, "the array has shape " + shape_text(shape.tuple) + ": every axis needs 1 to 2 000 000 000 values",
           "shape");
    header.size[a] = int(dims[std::size_t(a)]);
  }
  // C order: the last index varies fastest, so voxel (i, j, k) is array[i, j, k] in both orders.
  header.order = fortran.text == "True" ? std::array<int, 3>{0, 1, 2} : std::array<int, 3>{2, 1, 0};
  if (bytes_left(in) > std::uint64_t(checked_voxels(path, header.size)) * value_bytes(header.type))
    fail(path, "the file is longer than the array of shape " + shape_text(shape.tuple) + " of " +
                   value_type_name(header.type));
  read_payload(in, path, header, sink);
}

void write_npy(const std::string& path, const VolumeData& volume) {
  static const std::map<VoxelValueType, const char*> codes = {
      {VoxelValueType::Bool, "b1"},    {VoxelValueType::Int8, "i1"},    {VoxelValueType::Int16, "i2"},
      {VoxelValueType::Int32, "i4"},   {VoxelValueType::Int64, "i8"},   {VoxelValueType::UInt8, "u1"},
      {VoxelValueType::UInt16, "u2"},  {VoxelValueType::UInt32, "u4"},  {VoxelValueType::UInt64, "u8"},
      {VoxelValueType::Float32, "f4"}, {VoxelValueType::Float64, "f8"},
  };
  // The bytes are i fastest, which is numpy's Fortran order: written as they are, with
  // fortran_order True, numpy.load gives array[i, j, k] = voxel (i, j, k) without a transpose.
  const char order = value_bytes(volume.type) == 1 ? '|' : std::endian::native == std::endian::big ? '>' : '<';
  std::string dict = std::string("{'descr': '") + order + codes.at(volume.type) +
                     "', 'fortran_order': True, 'shape': (" + std::to_string(volume.size.x()) + ", " +
                     std::to_string(volume.size.y()) + ", " + std::to_string(volume.size.z()) + "), }";
  // numpy pads the header with spaces so that the values start at a multiple of 64 bytes.
  const std::size_t prefix = kMagicLength + 2 + 2;
  dict.append((64 - (prefix + dict.size() + 1) % 64) % 64, ' ');
  dict += '\n';
  OutputFile out(path, "numpy", true);
  std::fwrite(kMagic, 1, kMagicLength, out.get());
  const unsigned char version_and_length[4] = {1, 0, static_cast<unsigned char>(dict.size() & 0xff),
                                               static_cast<unsigned char>(dict.size() >> 8)};
  // A short write sets the stream's error flag, which commit() reports naming the file.
  (void)std::fwrite(version_and_length, 1, 4, out.get());
  (void)std::fwrite(dict.data(), 1, dict.size(), out.get());
  if (!volume.bytes.empty()) (void)std::fwrite(volume.bytes.data(), 1, volume.bytes.size(), out.get());
  out.commit();
}

}  // namespace corrlap::io_detail

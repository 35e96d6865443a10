// Stanford PLY reader (ASCII, binary little-endian) and binary little-endian writer.
#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/block_readers.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/corner_reserve.hpp>
#include <corrlap/io/detail/line_reader.hpp>
#include <corrlap/io/detail/mesh_records.hpp>
#include <corrlap/io/detail/text_writer.hpp>
#include <corrlap/io/detail/tokens.hpp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>
#include <type_traits>
#include <vector>

#include "mesh_io.hpp"

namespace corrlap {

// Binary payloads are copied with memcpy: the host must be little-endian like the files we write.
static_assert(std::endian::native == std::endian::little, "PLY binary I/O assumes a little-endian host");

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw IoError("PLY file '" + path + "': " + what);
}

// More elements than this is certainly a corrupt header (ids are stored as int).
constexpr std::uint64_t kMaxCount = std::uint64_t{1} << 31;
// Real headers have a few dozen lines; the bound keeps a header of junk lines cheap to reject.
constexpr std::size_t kMaxHeaderLines = 10000;

enum class Kind { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct TypeInfo {
  const char* names[2];
  Kind kind;
  int bytes;
};
constexpr TypeInfo kTypes[] = {
    {{"char", "int8"}, Kind::Int8, 1},        {{"uchar", "uint8"}, Kind::UInt8, 1},
    {{"short", "int16"}, Kind::Int16, 2},     {{"ushort", "uint16"}, Kind::UInt16, 2},
    {{"int", "int32"}, Kind::Int32, 4},       {{"uint", "uint32"}, Kind::UInt32, 4},
    {{"float", "float32"}, Kind::Float32, 4}, {{"double", "float64"}, Kind::Float64, 8},
};

const TypeInfo* find_type(const std::string& name) {
  for (const auto& t : kTypes)
    if (name == t.names[0] || name == t.names[1]) return &t;
  return nullptr;
}

bool is_integer(Kind k) { return k != Kind::Float32 && k != Kind::Float64; }

struct Property {
  std::string name;
  const TypeInfo* type = nullptr;        // value type (item type for lists)
  const TypeInfo* count_type = nullptr;  // non-null for lists
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

template <class T>
T load(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// One binary value as a double: exact for every PLY type.
inline double decode(Kind k, const char* p) {
  switch (k) {
    case Kind::Int8:
      return load<std::int8_t>(p);
    case Kind::UInt8:
      return load<std::uint8_t>(p);
    case Kind::Int16:
      return load<std::int16_t>(p);
    case Kind::UInt16:
      return load<std::uint16_t>(p);
    case Kind::Int32:
      return load<std::int32_t>(p);
    case Kind::UInt32:
      return load<std::uint32_t>(p);
    case Kind::Float32:
      return load<float>(p);
    case Kind::Float64:
      return load<double>(p);
  }
  return 0;
}

// The body of an ASCII file: whitespace-separated values, any number per line, parsed in place in
// the line reader's blocks. Line numbers count from the top of the file, header included.
class AsciiBody {
 public:
  AsciiBody(const std::string& path, io_detail::LineReader& in) : path_(path), in_(in), line_offset_(in.offset()) {}

  double read(const TypeInfo& t, const char* context) {
    if (!seek()) fail(path_, std::string("truncated data: end of file while reading ") + context);
    // The number is parsed where it starts and must end at a blank: one pass over its characters.
    if (is_integer(t.kind)) {
      std::int64_t i = 0;
      const bool minus = *cur_ == '-';
      if (parse_here(i)) return i == 0 && minus ? -0.0 : double(i);  // "-0" as before: -0.0
    } else {
      double v = 0;
      if (parse_here(v)) return v;
    }
    return read_slowly(t, context);
  }
  /// An integer token as an integer (false, nothing consumed, for anything else: read() says why).
  bool read_integer(std::int64_t& v) { return seek() && parse_here(v); }
  std::uint64_t remaining() const {
    const std::uint64_t pos = line_offset_ + std::uint64_t(cur_ - line_);
    return in_.file_size() > pos ? in_.file_size() - pos : 0;
  }
  /// Most values the rest of the body can hold: a digit and a separator each.
  std::size_t max_values(const TypeInfo&) const { return std::size_t((remaining() + 1) / 2); }
  std::string where() const { return "line " + std::to_string(in_.line_number()); }
  /// Only whitespace left; otherwise where() is the line of what is left.
  bool at_end() { return !seek(); }
  std::string what_is_left() const { return where(); }

 private:
  // To the next non-blank character, on this line or a later one; false at the end of the file.
  bool seek() {
    for (;;) {
      while (cur_ != end_ && io_detail::is_blank(*cur_)) ++cur_;
      if (cur_ != end_) return true;
      line_offset_ = in_.offset();
      std::string_view line;
      if (!in_.next(line)) {
        if (in_.error()) fail(path_, "read error");
        return false;
      }
      line_ = cur_ = line.data();
      end_ = cur_ + line.size();
    }
  }
  template <class T>
  bool parse_here(T& v) {
    const auto [ptr, ec] = std::from_chars(cur_, end_, v);
    if (ec != std::errc() || (ptr != end_ && !io_detail::is_blank(*ptr))) return false;
    cur_ = ptr;
    return true;
  }
  // The whole token: "3.0" or "1e2" for an integer property, or an error naming it.
  double read_slowly(const TypeInfo& t, const char* context) {
    const char* e = cur_;
    while (e != end_ && !io_detail::is_blank(*e)) ++e;
    const std::string_view tok(cur_, std::size_t(e - cur_));
    double v = 0;
    const auto [ptr, ec] = std::from_chars(cur_, e, v);
    if (ec != std::errc() || ptr != e)
      fail(path_, where() + ": malformed number '" + std::string(tok.substr(0, 40)) + "' in " + context);
    if (is_integer(t.kind) && !(std::isfinite(v) && v == std::floor(v)))
      fail(path_, where() + ": non-integer value '" + std::string(tok.substr(0, 40)) + "' for an integer property in " +
                      context);
    cur_ = e;
    return v;
  }

  const std::string& path_;
  io_detail::LineReader& in_;
  const char *line_ = nullptr, *cur_ = nullptr, *end_ = nullptr;  // the current line; cur_: next unread
  std::uint64_t line_offset_;                                     // file offset of line_
};

// The body of a binary file, taken from the line reader's blocks as they come.
class BinaryBody {
 public:
  BinaryBody(const std::string& path, io_detail::LineReader& in) : path_(path), in_(in) { sync(); }

  double read(const TypeInfo& t, const char* context) { return decode(t.kind, take(std::size_t(t.bytes), context)); }
  /// Pointer to the next `bytes` bytes (consumed).
  const char* take(std::size_t bytes, const char* context) {
    if (std::size_t(end_ - p_) < bytes && !fill(bytes))
      fail(path_, std::string("truncated binary data: end of file while reading ") + context);
    const char* p = p_;
    p_ += bytes;
    return p;
  }
  /// The next run of items of `bytes` bytes each, up to `most` of them, as many as the block
  /// holds; returns how many (0: the file ends before one more), their bytes at p (consumed).
  std::size_t run(std::size_t bytes, std::size_t most, const char*& p) {
    if (std::size_t(end_ - p_) < bytes && !fill(bytes)) return 0;
    const std::size_t n = std::min(most, std::size_t(end_ - p_) / bytes);
    p = p_;
    p_ += n * bytes;
    return n;
  }
  /// A run of at least one item.
  std::size_t take_run(std::size_t bytes, std::size_t most, const char*& p, const char* context) {
    const std::size_t n = run(bytes, most, p);
    if (n == 0) fail(path_, std::string("truncated binary data: end of file while reading ") + context);
    return n;
  }
  std::uint64_t offset() const { return in_.offset() + std::uint64_t(p_ - begin_); }
  std::uint64_t remaining() const { return in_.file_size() > offset() ? in_.file_size() - offset() : 0; }
  std::size_t max_values(const TypeInfo& t) const { return std::size_t(remaining() / std::uint64_t(t.bytes)); }
  std::string where() const { return "byte " + std::to_string(offset()); }
  bool at_end() { return p_ == end_ && !fill(1); }
  std::string what_is_left() const { return std::to_string(remaining()) + " bytes"; }

 private:
  void sync() {
    const std::string_view b = in_.buffered();
    begin_ = p_ = b.data();
    end_ = b.data() + b.size();
  }
  bool fill(std::size_t n) {
    in_.consume(std::size_t(p_ - begin_));
    const bool ok = in_.fill(n);
    sync();
    if (!ok && in_.error()) fail(path_, "read error");
    return ok;
  }

  const std::string& path_;
  io_detail::LineReader& in_;
  const char *begin_ = nullptr, *p_ = nullptr, *end_ = nullptr;  // the reader's buffered bytes; p_: next unread
};

// The vertex ids of one face, checked against the vertex count.
struct CornerSink {
  const std::string& path;
  const Property& list;
  std::int64_t vertices;
  FaceList& faces;

  [[noreturn]] void out_of_range(std::uint64_t face, double id) const {
    fail(path, "face " + std::to_string(face) + ", property '" + list.name + "': vertex index " +
                   io_detail::readable_number(id) + " out of range (" +
                   io_detail::readable_count(std::uint64_t(vertices)) + " vertices)");
  }
  void add(std::uint64_t face, double id) {
    const auto checked = io_detail::checked_integer(id, 0, vertices - 1);
    if (!checked) out_of_range(face, id);
    faces.add_corner(int(*checked));
  }
  void add_integer(std::uint64_t face, std::int64_t id) {
    if (id < 0 || id >= vertices) out_of_range(face, double(id));
    faces.add_corner(int(id));
  }
  template <class T>
  void add_integers(std::uint64_t face, const char* p, std::size_t n) {
    for (std::size_t k = 0; k < n; ++k, p += sizeof(T)) add_integer(face, std::int64_t(load<T>(p)));
  }
};

void read_corners(AsciiBody& body, CornerSink& sink, std::uint64_t face, std::size_t n) {
  const bool integers = is_integer(sink.list.type->kind);
  for (std::size_t k = 0; k < n; ++k) {
    std::int64_t id = 0;
    if (integers && body.read_integer(id))
      sink.add_integer(face, id);
    else
      sink.add(face, body.read(*sink.list.type, "face"));
  }
}

// Integer ids are checked as integers, whole runs at a time (the common int and uint lists).
void read_corners(BinaryBody& body, CornerSink& sink, std::uint64_t face, std::size_t n) {
  const TypeInfo& t = *sink.list.type;
  while (n > 0) {
    const char* p = nullptr;
    const std::size_t run = body.take_run(std::size_t(t.bytes), n, p, "face");
    n -= run;
    switch (t.kind) {
      case Kind::Int8:
        sink.add_integers<std::int8_t>(face, p, run);
        break;
      case Kind::UInt8:
        sink.add_integers<std::uint8_t>(face, p, run);
        break;
      case Kind::Int16:
        sink.add_integers<std::int16_t>(face, p, run);
        break;
      case Kind::UInt16:
        sink.add_integers<std::uint16_t>(face, p, run);
        break;
      case Kind::Int32:
        sink.add_integers<std::int32_t>(face, p, run);
        break;
      case Kind::UInt32:
        sink.add_integers<std::uint32_t>(face, p, run);
        break;
      case Kind::Float32:
      case Kind::Float64:
        for (std::size_t k = 0; k < run; ++k) sink.add(face, decode(t.kind, p + k * std::size_t(t.bytes)));
        break;
    }
  }
}

// Where a property's values go.
struct Target {
  enum What { Skip, Position, Scalar, Corners } what = Skip;
  int column = 0;            // Position: x, y or z
  double* values = nullptr;  // Scalar: the property's column
};

// What the body fills: positions, faces, and a column per other scalar property (empty otherwise).
struct Destination {
  PolygonMesh& mesh;
  std::vector<double*> vertex_columns, face_columns;  // per property; null: not kept
};

// The last properties named nx, ny and nz of an element (-1 when absent).
std::array<int, 3> normal_properties(const Element& e) {
  std::array<int, 3> n = {-1, -1, -1};
  for (std::size_t p = 0; p < e.properties.size(); ++p) {
    const auto& pr = e.properties[p];
    if (pr.count_type) continue;
    if (pr.name == "nx") n[0] = int(p);
    if (pr.name == "ny") n[1] = int(p);
    if (pr.name == "nz") n[2] = int(p);
  }
  return n;
}

// Every element in file order, value by value as the header describes them (other elements are
// read and dropped), then nothing but whitespace (ASCII) or nothing at all (binary).
template <class Body>
void read_elements(Body& body, const std::string& path, const std::vector<Element>& elements, const Element* vertex_el,
                   const Element* face_el, const int xyz[3], int face_list, const Destination& out) {
  const Eigen::Index nv = out.mesh.positions.rows();
  for (const auto& e : elements) {
    if (e.properties.empty()) continue;  // no bytes to read: no loop over an announced 2^31 entries
    const bool is_v = &e == vertex_el, is_f = &e == face_el;
    std::vector<Target> targets(e.properties.size());
    for (std::size_t p = 0; p < targets.size(); ++p) {
      Target& t = targets[p];
      if (is_v && !e.properties[p].count_type) {
        for (int a = 0; a < 3; ++a)
          if (int(p) == xyz[a]) t = {Target::Position, a, nullptr};
        if (t.what == Target::Skip && out.vertex_columns[p]) t = {Target::Scalar, 0, out.vertex_columns[p]};
      } else if (is_f && !e.properties[p].count_type) {
        if (out.face_columns[p]) t = {Target::Scalar, 0, out.face_columns[p]};
      } else if (is_f && int(p) == face_list) {
        t.what = Target::Corners;
      }
    }
    std::optional<io_detail::CornerReserve> reserve;
    std::optional<CornerSink> sink;
    if (is_f) {
      reserve.emplace(out.mesh.faces, std::size_t(e.count));
      sink.emplace(CornerSink{path, e.properties[std::size_t(face_list)], std::int64_t(nv), out.mesh.faces});
    }
    // Positions and normals must be finite; a named scalar may hold NaN (an undefined value), which
    // only the consumer that uses that scalar refuses (render_mesh).
    std::vector<char> must_be_finite(targets.size(), 0);
    for (std::size_t p = 0; p < targets.size(); ++p) {
      const std::string& name = e.properties[p].name;
      must_be_finite[p] = is_v && (targets[p].what == Target::Position || name == "nx" || name == "ny" || name == "nz");
    }
    auto store = [&](std::uint64_t i, std::size_t p, double v) {
      if (must_be_finite[p] && !std::isfinite(v))
        fail(path, "vertex " + std::to_string(i) + ": non-finite value of '" + e.properties[p].name + "'");
      const Target& t = targets[p];
      if (t.what == Target::Position)
        out.mesh.positions(Eigen::Index(i), t.column) = v;
      else if (t.what == Target::Scalar)
        t.values[i] = v;
    };
    std::uint64_t first = 0;  // entries before it are read
    if constexpr (std::is_same_v<Body, BinaryBody>) {
      // Binary records of scalars only (vertices, mostly) have one layout: decoded at fixed offsets,
      // whole blocks of records at a time. A last partial record is left to the loop below, which
      // names the value that is missing.
      std::vector<std::size_t> offsets;
      std::size_t record = 0;
      for (const auto& pr : e.properties) {
        offsets.push_back(record);
        record += pr.count_type ? 0 : std::size_t(pr.type->bytes);
      }
      const bool fixed = std::none_of(e.properties.begin(), e.properties.end(),
                                      [](const Property& pr) { return pr.count_type != nullptr; });
      for (const char* r = nullptr; fixed && first < e.count;) {
        const std::size_t n = body.run(record, std::size_t(e.count - first), r);
        if (n == 0) break;
        for (std::size_t k = 0; k < n; ++k, ++first, r += record)
          for (std::size_t p = 0; p < offsets.size(); ++p)
            store(first, p, decode(e.properties[p].type->kind, r + offsets[p]));
      }
    }
    for (std::uint64_t i = first; i < e.count; ++i) {
      for (std::size_t p = 0; p < e.properties.size(); ++p) {
        const Property& pr = e.properties[p];
        const Target& t = targets[p];
        if (!pr.count_type) {
          store(i, p, body.read(*pr.type, e.name.c_str()));
          continue;
        }
        const double cnt = body.read(*pr.count_type, e.name.c_str());
        const std::size_t most = body.max_values(*pr.type);
        const auto len = io_detail::checked_integer(cnt, 0, std::int64_t(kMaxCount));
        // Built only for a message: one string per list would cost as much as the parsing.
        auto list_at = [&] {
          return "element '" + e.name + "' #" + std::to_string(i) + ", property '" + pr.name + "' (" + body.where() +
                 "): ";
        };
        if (!len) fail(path, list_at() + "invalid list length " + io_detail::readable_number(cnt));
        if (std::uint64_t(*len) > most)
          fail(path, list_at() + "truncated data: list length " + io_detail::readable_count(std::uint64_t(*len)) +
                         ", the rest of the file holds at most " + io_detail::readable_count(most) + " values");
        const std::size_t n = std::size_t(*len);
        if (t.what == Target::Corners) {
          if (n < 3)
            fail(path, "face " + std::to_string(i) + " has " + std::to_string(n) + " corners (at least 3 needed)");
          reserve->before_face(n, most);
          out.mesh.faces.start_face();
          read_corners(body, *sink, i, n);
        } else {
          for (std::size_t k = 0; k < n; ++k) body.read(*pr.type, e.name.c_str());
        }
      }
    }
  }
  if (!body.at_end())
    fail(path,
         "trailing data after the last element (" + body.what_is_left() + "): header counts do not match the data");
}

bool is_identifier(const std::string& s) {
  if (s.empty()) return false;
  for (unsigned char c : s)
    if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

}  // namespace

// The header is read line by line from the reader's blocks, the body from the same blocks: at no
// time is more of the file in memory than one block (4 MiB) and the line or record being read.
PolygonMesh io_detail::read_ply(const std::string& path, MeshAttributes* attributes, std::size_t block_bytes) {
  io_detail::LineReader in(path, block_bytes);
  if (!in.is_open()) fail(path, "cannot open");
  if (in.file_size() == 0) fail(path, "empty file");
  // ---- header ----
  std::string line;
  auto next_line = [&] {
    std::string_view raw;
    if (!in.next(raw)) {
      if (in.error()) fail(path, "read error");
      return false;
    }
    line.assign(io_detail::without_cr(raw));
    return true;
  };
  if (!next_line() || line != "ply") fail(path, "not a PLY file (first line must be 'ply')");
  bool binary = false, have_format = false, ended = false;
  std::vector<Element> elements;
  while (next_line()) {
    const std::size_t lineno = in.line_number();
    if (lineno > kMaxHeaderLines)
      fail(path, "header longer than " + std::to_string(kMaxHeaderLines) + " lines (missing end_header?)");
    std::istringstream ls(line);
    std::string kw;
    if (!(ls >> kw)) continue;
    const std::string at = "header line " + std::to_string(lineno) + ": ";
    if (kw == "end_header") {
      ended = true;
      break;
    }
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") {
      std::string fmt, version;
      ls >> fmt >> version;
      if (fmt == "ascii")
        binary = false;
      else if (fmt == "binary_little_endian")
        binary = true;
      else if (fmt == "binary_big_endian")
        fail(path, at + "unsupported format binary_big_endian (supported: ascii, binary_little_endian)");
      else
        fail(path, at + "unknown format '" + fmt + "'");
      if (version != "1.0") fail(path, at + "unsupported PLY version '" + version + "'");
      have_format = true;
    } else if (kw == "element") {
      Element e;
      std::string count;
      if (!(ls >> e.name >> count)) fail(path, at + "malformed element line '" + line + "'");
      std::uint64_t c = 0;
      auto [p, ec] = std::from_chars(count.data(), count.data() + count.size(), c);
      if (ec == std::errc::result_out_of_range || (ec == std::errc() && c > kMaxCount))
        fail(path, at + "absurd element count " + count.substr(0, 40) + " for '" + e.name + "' (limit " +
                       io_detail::readable_count(kMaxCount) + ")");
      if (ec != std::errc() || p != count.data() + count.size())
        fail(path, at + "malformed element count '" + count.substr(0, 40) + "'");
      e.count = c;
      elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (elements.empty()) fail(path, at + "property before any element");
      Property prop;
      std::string type;
      ls >> type;
      if (type == "list") {
        std::string ct, it;
        ls >> ct >> it >> prop.name;
        prop.count_type = find_type(ct);
        prop.type = find_type(it);
        if (!prop.count_type || !prop.type || !is_integer(prop.count_type->kind))
          fail(path, at + "malformed list property '" + line + "'");
      } else {
        ls >> prop.name;
        prop.type = find_type(type);
        if (!prop.type) fail(path, at + "unknown property type '" + type + "'");
      }
      if (prop.name.empty()) fail(path, at + "property without a name");
      elements.back().properties.push_back(prop);
    } else {
      fail(path, at + "unknown header keyword '" + kw.substr(0, 40) + "'");
    }
  }
  if (!ended) fail(path, "header not terminated by end_header (truncated file?)");
  if (!have_format) fail(path, "header has no format line");

  // ---- locate what we need ----
  const Element* vertex_el = nullptr;
  const Element* face_el = nullptr;
  for (const auto& e : elements) {
    if (e.name == "vertex") vertex_el = &e;
    if (e.name == "face") face_el = &e;
  }
  if (!vertex_el) fail(path, "no 'vertex' element");
  if (!face_el) fail(path, "no 'face' element (point clouds are not meshes)");
  if (vertex_el->count == 0) fail(path, "no vertex");
  if (face_el->count == 0) fail(path, "no face");
  int xyz[3] = {-1, -1, -1};
  for (std::size_t p = 0; p < vertex_el->properties.size(); ++p) {
    const auto& pr = vertex_el->properties[p];
    for (int a = 0; a < 3; ++a)
      if (pr.name == std::string(1, char('x' + a)) && !pr.count_type) xyz[a] = int(p);
  }
  for (int a = 0; a < 3; ++a)
    if (xyz[a] < 0) fail(path, std::string("vertex element has no scalar property '") + char('x' + a) + "'");
  int face_list = -1;
  for (std::size_t p = 0; p < face_el->properties.size(); ++p) {
    const auto& pr = face_el->properties[p];
    if (pr.count_type && (pr.name == "vertex_indices" || pr.name == "vertex_index")) face_list = int(p);
  }
  if (face_list < 0) fail(path, "face element has no list property 'vertex_indices' or 'vertex_index'");

  // Reject absurd counts before allocating or looping: every entry of an element needs at least
  // the bytes of its properties (binary; a list its count) or one digit and one separator per
  // property (ASCII). Elements without properties occupy no bytes and are skipped without a loop.
  const double body_bytes = in.file_size() > in.offset() ? double(in.file_size() - in.offset()) : 0.0;
  {
    double needed = 0;
    for (const auto& e : elements) {
      double per = 0;
      for (const auto& pr : e.properties) per += binary ? (pr.count_type ? pr.count_type->bytes : pr.type->bytes) : 2;
      needed += per * double(e.count);
      if (needed - (binary ? 0 : 1) > body_bytes)
        fail(path, "truncated data: element '" + e.name + "' announces " + io_detail::readable_count(e.count) +
                       " entries; with the elements before it they need at least " +
                       io_detail::readable_bytes(needed - (binary ? 0 : 1)) + ", more than the " +
                       io_detail::readable_bytes(body_bytes) + " the file holds after the header");
    }
  }
  // Positions (24 bytes), one double per vertex property, and per face a double per property
  // plus an index vector (~40 bytes).
  io_detail::check_budget("PLY file '" + path + "'",
                          double(vertex_el->count) * (24.0 + 8.0 * double(vertex_el->properties.size())) +
                              double(face_el->count) * (40.0 + 8.0 * double(face_el->properties.size())),
                          io_detail::readable_count(vertex_el->count) + " vertices and " +
                              io_detail::readable_count(face_el->count) + " faces");
  PolygonMesh mesh;
  mesh.positions.resize(Eigen::Index(vertex_el->count), 3);
  // Wanted attributes only: every scalar property gets a column, except x, y, z (the positions);
  // nx, ny, nz together are read straight into the normals.
  MeshAttributes attr;
  std::vector<Eigen::VectorXd> vprops(vertex_el->properties.size()), fprops(face_el->properties.size());
  Destination out{mesh, std::vector<double*>(vprops.size()), std::vector<double*>(fprops.size())};
  auto columns = [&](const Element& e, bool is_vertex, std::vector<Eigen::VectorXd>& props, Eigen::MatrixX3d& normals,
                     std::vector<double*>& cols) {
    const auto n = normal_properties(e);
    const bool has_normals = n[0] >= 0 && n[1] >= 0 && n[2] >= 0;
    if (has_normals) normals.resize(Eigen::Index(e.count), 3);
    for (std::size_t p = 0; p < e.properties.size(); ++p) {
      const Property& pr = e.properties[p];
      if (pr.count_type || (is_vertex && (pr.name == "x" || pr.name == "y" || pr.name == "z"))) continue;
      const int normal = int(std::find(n.begin(), n.end(), int(p)) - n.begin());
      if (has_normals && normal < 3) {
        cols[p] = normals.col(normal).data();
      } else if (normal < 3 || (pr.name != "nx" && pr.name != "ny" && pr.name != "nz")) {
        props[p].resize(Eigen::Index(e.count));
        cols[p] = props[p].data();
      }  // else: an earlier nx, ny or nz, overridden by a later one of the same name
    }
  };
  if (attributes) {
    columns(*vertex_el, true, vprops, attr.vertex_normals, out.vertex_columns);
    columns(*face_el, false, fprops, attr.face_normals, out.face_columns);
  }
  // Corners are reserved as the faces come (io/detail/corner_reserve.hpp), not assumed triangles.
  if (binary) {
    BinaryBody body(path, in);
    read_elements(body, path, elements, vertex_el, face_el, xyz, face_list, out);
  } else {
    AsciiBody body(path, in);
    read_elements(body, path, elements, vertex_el, face_el, xyz, face_list, out);
  }

  if (attributes) {
    // Moved, not copied: a read holds each value once.
    auto collect = [](const Element& e, std::vector<Eigen::VectorXd>& props,
                      std::map<std::string, Eigen::VectorXd>& scalars) {
      for (std::size_t p = 0; p < e.properties.size(); ++p)
        if (props[p].size() != 0) scalars[e.properties[p].name] = std::move(props[p]);
    };
    collect(*vertex_el, vprops, attr.vertex_scalars);
    collect(*face_el, fprops, attr.face_scalars);
    *attributes = std::move(attr);
  }
  return mesh;
}

PolygonMesh read_ply(const std::string& path, MeshAttributes* attributes) {
  return io_detail::read_ply(path, attributes, io_detail::LineReader::kDefaultBlock);
}

void write_ply(const std::string& path, const PolygonMesh& mesh, const MeshAttributes& a) {
  const Eigen::Index nv = mesh.positions.rows();
  const Eigen::Index nf = Eigen::Index(mesh.faces.size());
  auto check_rows = [&](Eigen::Index rows, Eigen::Index expected, const std::string& what) {
    if (rows != expected)
      fail(path, what + " has " + std::to_string(rows) + " rows, expected " + std::to_string(expected));
  };
  if (a.vertex_normals.rows() != 0) check_rows(a.vertex_normals.rows(), nv, "vertex normals");
  if (a.face_normals.rows() != 0) check_rows(a.face_normals.rows(), nf, "face normals");
  auto check_scalars = [&](const std::map<std::string, Eigen::VectorXd>& s, Eigen::Index expected, const char* kind) {
    for (const auto& [name, v] : s) {
      if (!io_detail::ply_scalar_name_ok(name))
        fail(path, std::string(kind) + " scalar name '" + name + "' is not a valid, unreserved PLY property name");
      check_rows(v.size(), expected, std::string(kind) + " scalar '" + name + "'");
    }
  };
  check_scalars(a.vertex_scalars, nv, "vertex");
  check_scalars(a.face_scalars, nf, "face");
  std::size_t max_degree = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    max_degree = std::max(max_degree, mesh.faces[f].size());
    for (int id : mesh.faces[f])
      if (id < 0 || id >= nv)
        fail(path, "face " + std::to_string(f) + " refers to vertex " + std::to_string(id) + " (out of range)");
  }
  const bool wide = max_degree > 255;

  io_detail::PlyHeader header;
  header.vertices = nv;
  header.faces = nf;
  header.vertex_normals = a.vertex_normals.rows() > 0;
  header.face_normals = a.face_normals.rows() > 0;
  for (const auto& [name, v] : a.vertex_scalars) header.vertex_scalars.push_back(name);
  for (const auto& [name, v] : a.face_scalars) header.face_scalars.push_back(name);
  header.wide_faces = wide;
  for (const std::string& c : a.comments) {
    if (c.find_first_of("\r\n") != std::string::npos) fail(path, "a header comment holds a line break");
    header.comments.push_back(c);
  }

  // Streamed through the buffered writer: a temporary file that a non-finite value below removes.
  io_detail::TextWriter out(path, "PLY", /*binary=*/true);
  out.write(io_detail::ply_header(header));
  auto put = [&out](const auto& value) { out.write_bytes(&value, sizeof(value)); };
  // Positions, normals and scalars: no NaN or infinity reaches the file (the element is named).
  auto put_finite = [&](double value, const char* element, Eigen::Index index, const std::string* scalar = nullptr) {
    if (!std::isfinite(value))
      io_detail::require_finite(value, path, "PLY", scalar ? "scalar '" + *scalar + "' at " + element : element,
                                (long long)index);
    put(value);
  };
  for (Eigen::Index v = 0; v < nv; ++v) {
    for (int c = 0; c < 3; ++c) put_finite(double(mesh.positions(v, c)), "vertex", v);
    if (a.vertex_normals.rows())
      for (int c = 0; c < 3; ++c) put_finite(double(a.vertex_normals(v, c)), "normal at vertex", v);
    for (const auto& [name, s] : a.vertex_scalars) put_finite(double(s[v]), "vertex", v, &name);
  }
  for (Eigen::Index f = 0; f < nf; ++f) {
    const auto& face = mesh.faces[std::size_t(f)];
    io_detail::put_ply_face_list(out, face, face.size(), wide);
    if (a.face_normals.rows())
      for (int c = 0; c < 3; ++c) put_finite(double(a.face_normals(f, c)), "normal at face", f);
    for (const auto& [name, s] : a.face_scalars) put_finite(double(s[f]), "face", f, &name);
  }
  out.commit();
}

namespace io_detail {

bool ply_scalar_name_ok(const std::string& name) {
  return is_identifier(name) && name != "x" && name != "y" && name != "z" && name != "nx" && name != "ny" &&
         name != "nz" && name != "vertex_indices" && name != "vertex_index";
}

std::string ply_header(const PlyHeader& h) {
  std::ostringstream o;
  o << "ply\nformat binary_little_endian 1.0\ncomment written by corrlap\n";
  for (const std::string& c : h.comments) o << "comment " << c << "\n";
  o << "element vertex " << h.vertices << "\nproperty double x\nproperty double y\nproperty double z\n";
  if (h.vertex_normals) o << "property double nx\nproperty double ny\nproperty double nz\n";
  for (const std::string& name : h.vertex_scalars) o << "property double " << name << "\n";
  o << "element face " << h.faces << "\nproperty list " << (h.wide_faces ? "uint" : "uchar") << " int vertex_indices\n";
  if (h.face_normals) o << "property double nx\nproperty double ny\nproperty double nz\n";
  for (const std::string& name : h.face_scalars) o << "property double " << name << "\n";
  o << "end_header\n";
  return o.str();
}

}  // namespace io_detail

}  // namespace corrlap

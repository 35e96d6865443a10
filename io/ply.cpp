// Stanford PLY reader (ASCII, binary little-endian) and binary little-endian writer.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <corrlap/io/detail/text_writer.hpp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
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

// Sequential reader of the body, ASCII (tokens) or binary (bytes), with bounds checks.
class BodyReader {
 public:
  BodyReader(const std::string& path, const std::string& data, std::size_t pos, bool binary, std::size_t header_lines)
      : path_(path), data_(data), pos_(pos), binary_(binary), line_(header_lines + 1) {}

  double read(const TypeInfo& t, const char* context) {
    return binary_ ? read_binary(t, context) : read_ascii(t, context);
  }
  std::size_t remaining() const { return data_.size() - pos_; }
  /// Most values of type t that the rest of the body can hold (ASCII: a digit and a separator each).
  std::size_t max_values(const TypeInfo& t) const {
    return binary_ ? remaining() / std::size_t(t.bytes) : (remaining() + 1) / 2;
  }
  bool binary() const { return binary_; }
  std::string where() const {
    if (binary_) return "byte " + std::to_string(pos_);
    return "line " + std::to_string(line_);
  }
  bool only_whitespace_left() {
    if (binary_) return pos_ == data_.size();
    skip_space();
    return pos_ == data_.size();
  }

 private:
  void skip_space() {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) {
      if (data_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  double read_ascii(const TypeInfo& t, const char* context) {
    skip_space();
    if (pos_ == data_.size()) fail(path_, std::string("truncated data: end of file while reading ") + context);
    const char* b = data_.data() + pos_;
    std::size_t e = pos_;
    while (e < data_.size() && !std::isspace(static_cast<unsigned char>(data_[e]))) ++e;
    const char* end = data_.data() + e;
    double v = 0;
    auto [ptr, ec] = std::from_chars(b, end, v);
    if (ec != std::errc() || ptr != end)
      fail(path_, "line " + std::to_string(line_) + ": malformed number '" +
                      std::string(b, std::min<std::size_t>(end - b, 40)) + "' in " + context);
    if (is_integer(t.kind) && !(std::isfinite(v) && v == std::floor(v)))
      fail(path_, "line " + std::to_string(line_) + ": non-integer value '" +
                      std::string(b, std::min<std::size_t>(end - b, 40)) + "' for an integer property in " + context);
    pos_ = e;
    return v;
  }
  double read_binary(const TypeInfo& t, const char* context) {
    if (remaining() < std::size_t(t.bytes))
      fail(path_, std::string("truncated binary data: end of file while reading ") + context);
    const char* p = data_.data() + pos_;
    pos_ += std::size_t(t.bytes);
    switch (t.kind) {
      case Kind::Int8: {
        std::int8_t v;
        std::memcpy(&v, p, 1);
        return v;
      }
      case Kind::UInt8: {
        std::uint8_t v;
        std::memcpy(&v, p, 1);
        return v;
      }
      case Kind::Int16: {
        std::int16_t v;
        std::memcpy(&v, p, 2);
        return v;
      }
      case Kind::UInt16: {
        std::uint16_t v;
        std::memcpy(&v, p, 2);
        return v;
      }
      case Kind::Int32: {
        std::int32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case Kind::UInt32: {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case Kind::Float32: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case Kind::Float64: {
        double v;
        std::memcpy(&v, p, 8);
        return v;
      }
    }
    return 0;
  }

  const std::string& path_;
  const std::string& data_;
  std::size_t pos_;
  bool binary_;
  std::size_t line_;
};

// The whole file, read straight into a string of its size (no stream buffer copies).
std::string read_file(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> in(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!in) fail(path, "cannot open");
  std::string data(io_detail::file_size(path), '\0');
  data.resize(std::fread(data.data(), 1, data.size(), in.get()));
  if (std::ferror(in.get())) fail(path, "read error");
  return data;
}

bool is_identifier(const std::string& s) {
  if (s.empty()) return false;
  for (unsigned char c : s)
    if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

}  // namespace

PolygonMesh read_ply(const std::string& path, MeshAttributes* attributes) {
  const std::string data = read_file(path);
  if (data.empty()) fail(path, "empty file");
  // ---- header ----
  std::size_t pos = 0, lineno = 0;
  auto next_line = [&](std::string& line) {
    if (pos >= data.size()) return false;
    std::size_t e = data.find('\n', pos);
    if (e == std::string::npos) e = data.size();
    line = data.substr(pos, e - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = std::min(data.size(), e + 1);
    ++lineno;
    return true;
  };
  std::string line;
  if (!next_line(line) || line != "ply") fail(path, "not a PLY file (first line must be 'ply')");
  bool binary = false, have_format = false, ended = false;
  std::vector<Element> elements;
  while (next_line(line)) {
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

  BodyReader body(path, data, pos, binary, lineno);
  // Reject absurd counts before allocating or looping: every entry of an element needs at least
  // the bytes of its properties (binary; a list its count) or one digit and one separator per
  // property (ASCII). Elements without properties occupy no bytes and are skipped without a loop.
  {
    double needed = 0;
    for (const auto& e : elements) {
      double per = 0;
      for (const auto& pr : e.properties) per += binary ? (pr.count_type ? pr.count_type->bytes : pr.type->bytes) : 2;
      needed += per * double(e.count);
      if (needed - (binary ? 0 : 1) > double(body.remaining()))
        fail(path, "truncated data: element '" + e.name + "' announces " + io_detail::readable_count(e.count) +
                       " entries; with the elements before it they need at least " +
                       io_detail::readable_bytes(needed - (binary ? 0 : 1)) + ", more than the " +
                       io_detail::readable_bytes(double(body.remaining())) + " the file holds after the header");
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
  const Eigen::Index nv = Eigen::Index(vertex_el->count);
  mesh.positions.resize(nv, 3);
  // Scalar properties other than x, y, z get a column each (x, y, z go straight to the positions).
  std::vector<Eigen::VectorXd> vprops(vertex_el->properties.size()), fprops(face_el->properties.size());
  for (std::size_t p = 0; p < vprops.size(); ++p)
    if (!vertex_el->properties[p].count_type && int(p) != xyz[0] && int(p) != xyz[1] && int(p) != xyz[2])
      vprops[p].resize(nv);
  for (std::size_t p = 0; p < fprops.size(); ++p)
    if (!face_el->properties[p].count_type) fprops[p].resize(Eigen::Index(face_el->count));
  mesh.faces.reserve(std::size_t(face_el->count), 3 * std::size_t(face_el->count));

  for (const auto& e : elements) {
    const bool is_v = &e == vertex_el, is_f = &e == face_el;
    const std::string ctx_base = "element '" + e.name + "' #";
    if (e.properties.empty()) continue;  // no bytes to read: no loop over an announced 2^31 entries
    for (std::uint64_t i = 0; i < e.count; ++i) {
      for (std::size_t p = 0; p < e.properties.size(); ++p) {
        const Property& pr = e.properties[p];
        if (!pr.count_type) {
          const double v = body.read(*pr.type, e.name.c_str());
          if (is_v) {
            if (!std::isfinite(v))
              fail(path, "vertex " + std::to_string(i) + ": non-finite value of '" + pr.name + "'");
            if (int(p) == xyz[0] || int(p) == xyz[1] || int(p) == xyz[2])
              mesh.positions(Eigen::Index(i), int(p) == xyz[0] ? 0 : int(p) == xyz[1] ? 1 : 2) = v;
            else
              vprops[p][Eigen::Index(i)] = v;
          } else if (is_f) {
            fprops[p][Eigen::Index(i)] = v;
          }
          continue;
        }
        const double cnt = body.read(*pr.count_type, e.name.c_str());
        const std::size_t most = body.max_values(*pr.type);
        const auto len = io_detail::checked_integer(cnt, 0, std::int64_t(kMaxCount));
        const std::string list_at =
            ctx_base + std::to_string(i) + ", property '" + pr.name + "' (" + body.where() + "): ";
        if (!len) fail(path, list_at + "invalid list length " + io_detail::readable_number(cnt));
        if (std::uint64_t(*len) > most)
          fail(path, list_at + "truncated data: list length " + io_detail::readable_count(std::uint64_t(*len)) +
                         ", the rest of the file holds at most " + io_detail::readable_count(most) + " values");
        const std::size_t n = std::size_t(*len);
        if (is_f && int(p) == face_list) {
          if (n < 3)
            fail(path, "face " + std::to_string(i) + " has " + std::to_string(n) + " corners (at least 3 needed)");
          mesh.faces.start_face();
          for (std::size_t k = 0; k < n; ++k) {
            const double id = body.read(*pr.type, "face");
            const auto checked = io_detail::checked_integer(id, 0, std::int64_t(nv) - 1);
            if (!checked)
              fail(path, "face " + std::to_string(i) + ", property '" + pr.name + "': vertex index " +
                             io_detail::readable_number(id) + " out of range (" +
                             io_detail::readable_count(std::uint64_t(nv)) + " vertices)");
            mesh.faces.add_corner(int(*checked));
          }
        } else {
          for (std::size_t k = 0; k < n; ++k) body.read(*pr.type, e.name.c_str());
        }
      }
    }
  }
  if (!body.only_whitespace_left() && binary)
    fail(path, "trailing data after the last element (" + std::to_string(body.remaining()) +
                   " bytes): header counts do not match the data");
  if (!body.only_whitespace_left())
    fail(path, "trailing data after the last element (" + body.where() + "): header counts do not match the data");

  if (attributes) {
    *attributes = MeshAttributes{};
    auto collect = [](const Element& e, const std::vector<Eigen::VectorXd>& props,
                      std::map<std::string, Eigen::VectorXd>& scalars, Eigen::MatrixX3d& normals, bool is_vertex) {
      int n[3] = {-1, -1, -1};
      for (std::size_t p = 0; p < e.properties.size(); ++p) {
        const auto& pr = e.properties[p];
        if (pr.count_type) continue;
        if (pr.name == "nx")
          n[0] = int(p);
        else if (pr.name == "ny")
          n[1] = int(p);
        else if (pr.name == "nz")
          n[2] = int(p);
        else if (!(is_vertex && (pr.name == "x" || pr.name == "y" || pr.name == "z")))
          scalars[pr.name] = props[p];
      }
      if (n[0] >= 0 && n[1] >= 0 && n[2] >= 0) {
        normals.resize(Eigen::Index(e.count), 3);
        for (int a = 0; a < 3; ++a) normals.col(a) = props[std::size_t(n[a])];
      } else {
        for (int a = 0; a < 3; ++a)
          if (n[a] >= 0) scalars[e.properties[std::size_t(n[a])].name] = props[std::size_t(n[a])];
      }
    };
    collect(*vertex_el, vprops, attributes->vertex_scalars, attributes->vertex_normals, true);
    collect(*face_el, fprops, attributes->face_scalars, attributes->face_normals, false);
  }
  return mesh;
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
      if (!is_identifier(name) || name == "x" || name == "y" || name == "z" || name == "nx" || name == "ny" ||
          name == "nz" || name == "vertex_indices" || name == "vertex_index")
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

  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\ncomment written by corrlap\n";
  h << "element vertex " << nv << "\nproperty double x\nproperty double y\nproperty double z\n";
  if (a.vertex_normals.rows()) h << "property double nx\nproperty double ny\nproperty double nz\n";
  for (const auto& [name, v] : a.vertex_scalars) h << "property double " << name << "\n";
  h << "element face " << nf << "\nproperty list " << (wide ? "uint" : "uchar") << " int vertex_indices\n";
  if (a.face_normals.rows()) h << "property double nx\nproperty double ny\nproperty double nz\n";
  for (const auto& [name, v] : a.face_scalars) h << "property double " << name << "\n";
  h << "end_header\n";

  // Streamed through the buffered writer: a temporary file that a non-finite value below removes.
  io_detail::TextWriter out(path, "PLY", /*binary=*/true);
  out.write(h.str());
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
    if (wide)
      put(std::uint32_t(face.size()));
    else
      put(std::uint8_t(face.size()));
    for (int id : face) put(std::int32_t(id));
    if (a.face_normals.rows())
      for (int c = 0; c < 3; ++c) put_finite(double(a.face_normals(f, c)), "normal at face", f);
    for (const auto& [name, s] : a.face_scalars) put_finite(double(s[f]), "face", f, &name);
  }
  out.commit();
}

}  // namespace corrlap

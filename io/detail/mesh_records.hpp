#pragma once
// The records of the mesh writers (internal): one formatting of a PLY or OBJ header, vertex and
// face, used by write_ply / write_obj on a whole mesh and by mesh_parts.hpp on pieces of one, so
// that a file written in pieces is byte for byte the file written whole.
#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace corrlap::io_detail {

/// Appends to a string what TextWriter appends to a file, with the same formatting.
class StringSink {
 public:
  explicit StringSink(std::string& out) : out_(out) {}
  void write(char c) { out_.push_back(c); }
  void write(std::string_view s) { out_.append(s); }
  void write_bytes(const void* data, std::size_t n) { out_.append(static_cast<const char*>(data), n); }
  void write_double(double v) {
    char buffer[32];
    out_.append(buffer, std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::general, 17).ptr);
  }
  template <class I>
  void write_int(I v) {
    char buffer[32];
    out_.append(buffer, std::to_chars(buffer, buffer + sizeof buffer, v).ptr);
  }

 private:
  std::string& out_;
};

/// What a binary PLY file's header declares.
struct PlyHeader {
  std::int64_t vertices = 0, faces = 0;
  bool vertex_normals = false, face_normals = false;
  std::vector<std::string> vertex_scalars, face_scalars;  ///< names, in the file's order
  bool wide_faces = false;                                ///< uint face sizes (a face of more than 255 corners)
  std::vector<std::string> comments;                      ///< without line breaks (checked by the caller)
};
std::string ply_header(const PlyHeader& h);

/// A name write_ply accepts for a scalar property: a PLY identifier that is not x, y, z, nx, ny, nz,
/// vertex_indices or vertex_index.
bool ply_scalar_name_ok(const std::string& name);

/// OBJ's first lines: the counts, then the comments.
std::string obj_header(std::int64_t vertices, std::int64_t faces, const std::vector<std::string>& comments);

/// "v x y z\n" with 17 significant digits.
template <class Sink>
void put_obj_vertex(Sink& out, double x, double y, double z) {
  out.write('v');
  for (double c : {x, y, z}) {
    out.write(' ');
    out.write_double(c);
  }
  out.write('\n');
}

/// "f a b c ...\n" from 0-based ids.
template <class Sink, class Ids>
void put_obj_face(Sink& out, const Ids& ids) {
  out.write('f');
  for (auto id : ids) {
    out.write(' ');
    out.write_int(std::int64_t(id) + 1);
  }
  out.write('\n');
}

/// A PLY face's list: its size (uchar, or uint when wide) and its 32-bit ids.
template <class Sink, class Ids>
void put_ply_face_list(Sink& out, const Ids& ids, std::size_t size, bool wide) {
  if (wide) {
    const auto n = std::uint32_t(size);
    out.write_bytes(&n, sizeof n);
  } else {
    const auto n = std::uint8_t(size);
    out.write_bytes(&n, sizeof n);
  }
  for (auto id : ids) {
    const auto v = std::int32_t(id);
    out.write_bytes(&v, sizeof v);
  }
}

}  // namespace corrlap::io_detail

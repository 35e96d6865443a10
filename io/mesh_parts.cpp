#include "mesh_parts.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/mesh_records.hpp>
#include <corrlap/io/detail/output_file.hpp>

namespace corrlap {

namespace {

bool is_ply(const MeshFileLayout& layout) { return file_extension(layout.path) == "ply"; }

// The format's name in messages, as write_ply and write_obj name it.
const char* format_name(const MeshFileLayout& layout) { return is_ply(layout) ? "PLY" : "OBJ"; }

}  // namespace

MeshFileLayout mesh_file_layout(const std::string& path, std::int64_t vertices, std::int64_t faces,
                                const MeshAttributes& attributes) {
  const std::string ext = file_extension(path);
  if (ext != "ply" && ext != "obj")
    throw IoError("mesh file '" + path + "': unsupported extension '" + ext + "' for writing (supported: .obj, .ply)");
  if (vertices < 0 || faces < 0) throw IoError("mesh file '" + path + "': negative vertex or face count");
  MeshFileLayout layout;
  layout.path = path;
  layout.vertices = vertices;
  layout.faces = faces;
  const std::string what = std::string(ext == "ply" ? "PLY" : "OBJ") + " file '" + path + "': ";
  for (const std::string& c : attributes.comments)
    if (c.find_first_of("\r\n") != std::string::npos) throw IoError(what + "a header comment holds a line break");
  layout.comments = attributes.comments;
  if (ext == "obj") return layout;  // OBJ writes the comments only, as write_mesh
  if (attributes.face_normals.rows() > 0 || !attributes.face_scalars.empty())
    throw IoError(what + "face attributes are not written in pieces");
  // PLY ids are 32-bit.
  if (vertices > std::int64_t(INT32_MAX)) throw IoError(what + "more vertices than 32-bit PLY ids can number");
  layout.vertex_normals = attributes.vertex_normals.rows() > 0;
  for (const auto& [name, v] : attributes.vertex_scalars) {
    if (!io_detail::ply_scalar_name_ok(name))
      throw IoError(what + "vertex scalar name '" + name + "' is not a valid, unreserved PLY property name");
    layout.vertex_scalars.push_back(name);
  }
  return layout;
}

std::string mesh_file_header(const MeshFileLayout& layout) {
  if (!is_ply(layout)) return io_detail::obj_header(layout.vertices, layout.faces, layout.comments);
  io_detail::PlyHeader h;
  h.vertices = layout.vertices;
  h.faces = layout.faces;
  h.vertex_normals = layout.vertex_normals;
  h.vertex_scalars = layout.vertex_scalars;
  h.comments = layout.comments;
  return io_detail::ply_header(h);
}

std::string mesh_file_vertices(const MeshFileLayout& layout, std::int64_t first, const Eigen::MatrixX3d& positions,
                               const MeshAttributes& attributes) {
  const Eigen::Index k = positions.rows();
  const std::string what = std::string(format_name(layout)) + " file '" + layout.path + "': ";
  if (first < 0 || first + k > layout.vertices)
    throw IoError(what + "vertices " + std::to_string(first) + " .. " + std::to_string(first + k - 1) +
                  " are not among its " + std::to_string(layout.vertices));
  const bool ply = is_ply(layout);
  if (ply) {
    if (layout.vertex_normals != (attributes.vertex_normals.rows() > 0) ||
        (layout.vertex_normals && attributes.vertex_normals.rows() != k))
      throw IoError(what + "the vertex normals do not match the layout (one row per vertex written)");
    if (attributes.vertex_scalars.size() != layout.vertex_scalars.size())
      throw IoError(what + "the vertex scalars do not match the layout");
    std::size_t i = 0;
    for (const auto& [name, v] : attributes.vertex_scalars)
      if (name != layout.vertex_scalars[i++] || v.size() != k)
        throw IoError(what + "vertex scalar '" + name + "' does not match the layout (one value per vertex written)");
  }
  std::string out;
  io_detail::StringSink sink(out);
  // Error messages count OBJ's vertices from 1 and PLY's from 0, as write_obj and write_ply do.
  const long long shown = ply ? 0 : 1;
  for (Eigen::Index r = 0; r < k; ++r) {
    const long long id = (long long)(first + r);
    for (int c = 0; c < 3; ++c)
      io_detail::require_finite(positions(r, c), layout.path, format_name(layout), "vertex", id + shown);
    if (!ply) {
      io_detail::put_obj_vertex(sink, positions(r, 0), positions(r, 1), positions(r, 2));
      continue;
    }
    for (int c = 0; c < 3; ++c) sink.write_bytes(&positions(r, c), sizeof(double));
    if (layout.vertex_normals)
      for (int c = 0; c < 3; ++c) {
        const double n = attributes.vertex_normals(r, c);
        io_detail::require_finite(n, layout.path, "PLY", "normal at vertex", id);
        sink.write_bytes(&n, sizeof n);
      }
    for (const auto& [name, v] : attributes.vertex_scalars) {
      const double value = v[r];
      io_detail::require_finite(value, layout.path, "PLY", "scalar '" + name + "' at vertex", id);
      sink.write_bytes(&value, sizeof value);
    }
  }
  return out;
}

std::string mesh_file_faces(const MeshFileLayout& layout, const QuadFaces& faces) {
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int c = 0; c < 4; ++c)
      if (faces(f, c) < 0 || faces(f, c) >= layout.vertices)
        throw IoError(std::string(format_name(layout)) + " file '" + layout.path + "': a face refers to vertex " +
                      std::to_string(faces(f, c)) + " (out of range)");
  std::string out;
  io_detail::StringSink sink(out);
  const bool ply = is_ply(layout);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const auto row = faces.row(f);
    if (ply)
      io_detail::put_ply_face_list(sink, row, 4, false);
    else
      io_detail::put_obj_face(sink, row);
  }
  return out;
}

}  // namespace corrlap

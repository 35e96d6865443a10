#include "mesh_io.hpp"

#include <algorithm>
#include <cctype>
#include <corrlap/core/error.hpp>

namespace corrlap {

std::string file_extension(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && slash > dot)) return "";
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

PolygonMesh read_mesh(const std::string& path, MeshAttributes* attributes) {
  const std::string ext = file_extension(path);
  if (ext == "ply") return read_ply(path, attributes);
  if (attributes) *attributes = MeshAttributes{};  // OBJ and OFF carry no attributes here
  if (ext == "obj") return read_obj(path);
  if (ext == "off") return read_off(path);
  throw IoError("mesh file '" + path + "': unsupported extension '" + ext + "' (supported: .obj, .ply, .off)");
}

void write_mesh(const std::string& path, const PolygonMesh& mesh, const MeshAttributes& attributes) {
  const std::string ext = file_extension(path);
  if (ext == "obj") return write_obj(path, mesh, attributes.comments);  // OBJ has no place for the others
  if (ext == "ply") return write_ply(path, mesh, attributes);
  throw IoError("mesh file '" + path + "': unsupported extension '" + ext + "' for writing (supported: .obj, .ply)");
}

}  // namespace corrlap

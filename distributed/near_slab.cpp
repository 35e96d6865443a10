#include "near_slab.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <string>

#include "distributed_halo.hpp"

namespace corrlap {

NearSlabNormals true_normals_near_slab(const ImplicitShape& shape, const SlabSource& source,
                                       const DistributedSurface& surface, int columns) {
  if (columns < 1)
    throw InputError("distributed normals: at least 1 column beyond the slab, got " + std::to_string(columns));
  // The halo of `columns` holds exactly the faces within `columns` of the slab, in serial order.
  DistributedHalo halo = distributed_halo(source, surface, columns);
  NearSlabNormals out;
  out.columns = columns;
  out.face_normals = true_face_normals(shape, halo.mesh);
  out.owned_vertices.assign(std::size_t(surface.num_owned), -1);
  for (std::size_t f = 0; f < halo.owned_faces.size(); ++f)
    for (int c = 0; c < 4; ++c) {
      const int v = surface.mesh.faces(Eigen::Index(f), c);
      if (v < surface.num_owned) out.owned_vertices[std::size_t(v)] = halo.mesh.faces(halo.owned_faces[f], c);
    }
  out.mesh = std::move(halo.mesh);
  out.face_ids = std::move(halo.face_ids);
  out.pointels = std::move(halo.pointels);
  set_vertex_normals_from_faces(out);
  return out;
}

void set_vertex_normals_from_faces(NearSlabNormals& near) {
  near.vertex_normals = vertex_normals_from_face_normals(near.face_normals, near.mesh.faces, near.mesh.num_vertices());
  // A vertex at the ragged edge, missing faces, can sum to zero where its whole fan would not.
  for (int f = 0; f < near.mesh.num_faces(); ++f)
    for (int c = 0; c < 4; ++c)
      if (near.vertex_normals.row(near.mesh.faces(f, c)).squaredNorm() == 0.0)
        near.vertex_normals.row(near.mesh.faces(f, c)) = near.face_normals.row(f);
}

}  // namespace corrlap

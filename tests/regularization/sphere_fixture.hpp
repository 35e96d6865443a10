#pragma once
// sphere1 at h = 0.1 (~3.8k vertices) with its exact vertex normals: the surface the
// regularization tests start from. Built once per test executable.
#include <corrlap/corrlap.hpp>

namespace corrlap::test {

struct RegularizationSphere {
  SurfelMesh mesh;
  NormalFields normals;  ///< true face normals; vertex normals exact (radial)
};

inline const RegularizationSphere& regularization_sphere() {
  static const RegularizationSphere s = [] {
    const ImplicitShape shape = make_implicit_shape("sphere1");
    RegularizationSphere r;
    r.mesh = extract_surface(digitize(shape, {.h = 0.1, .min_aabb = -1.5, .max_aabb = 1.5}));
    NormalRequest request;
    request.source = NormalSource::True;
    r.normals = resolve_normals(r.mesh, NormalKind::Vertex, request, &shape);
    r.normals.vertex = exact_vertex_normals(shape, r.mesh);
    return r;
  }();
  return s;
}

}  // namespace corrlap::test

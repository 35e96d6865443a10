#pragma once
// The regular icosahedron (vertices at distance sqrt(1 + t^2) from 0, t the golden ratio), outward
// oriented: the coarse closed mesh that the subdivision, closest-point and cotan-study tests refine.
#include <cmath>
#include <corrlap/surface/loop_subdivision.hpp>

namespace corrlap::test {

inline TriangleMesh icosahedron() {
  const double t = (1 + std::sqrt(5.0)) / 2;
  TriangleMesh m;
  m.positions.resize(12, 3);
  m.positions << -1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, 0, 0, -1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, t, 0, -1, t, 0, 1, -t,
      0, -1, -t, 0, 1;
  m.triangles.resize(20, 3);
  m.triangles << 0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9,
      4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1;
  return m;
}

}  // namespace corrlap::test

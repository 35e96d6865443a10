#pragma once
// Connectivity-only structure of the interpolated global-projection Laplacian (docs/math.md §3.6a).
// Internal header.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "quad_row_gather.hpp"

namespace corrlap::detail {

// Connectivity-only part of the global-projection Laplacian (docs/math.md §3.6a), everything the value
// passes need so that they only stream numbers: per edge its incidences (with the factor
// s_{f,i} / n_e) and their element slots; per column its sorted rows, the positions of the corners
// of each incident face, and its edges (ascending) with the positions of their element vertices.
// Held by QuadPattern (built on first use) or built for one assembly without a pattern.
struct ProjectionPattern {
  int k = 0, num_edges = 0;
  // Edge rows r_e of P D0 (per edge, k values, the first size[e] used).
  std::vector<std::uint8_t> size;
  std::vector<int> inc_start;          // #E + 1
  std::vector<int> inc_row;            // 4 f + i: row i of P_f D
  std::vector<double> inc_coef;        // s_{f,i} / n_e (docs/math.md §0 sign, flat averaged over n_e faces)
  std::vector<std::uint8_t> inc_slot;  // 4 per incidence: element slot of corner j
  // Columns of L.
  std::vector<int> outer, inner;
  bool wide = false;                    // column positions stored as int (a column > 255 rows)
  std::vector<std::uint8_t> face_pos8;  // 4 per vertex incidence (vc order): position of corner j
  std::vector<int> face_pos32;
  std::vector<int> ce_start, ce_edge;  // edges of the faces around v, ascending
  std::vector<std::uint8_t> ce_sv;     // element slot of v in that edge
  std::vector<std::uint8_t> ce_pos8;   // k per column edge: position of element slot s
  std::vector<int> ce_pos32;
};

/// Builds the projection pattern of the quad mesh `faces` (F faces, 4 ids each) with incidence vc.
/// Throws InputError when an edge has more than 62 incident faces.
std::unique_ptr<ProjectionPattern> build_projection_pattern(const int* faces, int F, const VertexCorners& vc);

/// Bytes held by p.
std::size_t memory_bytes(const ProjectionPattern& p);

}  // namespace corrlap::detail

#include "projection_pattern.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <corrlap/core/error.hpp>

namespace corrlap::detail {

namespace {

// Elements of the global-projection Laplacian (docs/math.md §3.6a): one per edge, on the union of the
// vertices of the edge's faces (6 for an interior manifold edge), padded to a common size.
struct EdgeElements {
  int k = 0;                           // padded element size
  std::vector<int> ids;                // #E x k vertex ids (padding repeats the first id)
  std::vector<std::uint8_t> size;      // distinct vertices of each element
  std::vector<int> start;              // incidences of edge e: [start[e], start[e+1])
  std::vector<int> inc_face;           // face of the incidence
  std::vector<std::int8_t> inc_local;  // local edge index i in that face
  std::vector<std::int8_t> inc_slot;   // 4 slots per incidence: element slot of corner j
  std::vector<int> corner_edge;        // edge index of local edge (f, i), 4 #F
  int num_edges = 0;
};

// Edges found locally from the vertex -> corner incidence (no global sort): the faces sharing
// local edge i of f are the faces around v_i that have v_{i+1} as a neighbouring corner. An edge
// is represented by its incidence of smallest face; its index is the rank of that representative.
EdgeElements build_edge_elements(const int* faces, int F, const VertexCorners& vc) {
  EdgeElements el;
  std::vector<int> key(std::size_t(F) * 4), count(std::size_t(F) * 4);
  auto for_each_incidence = [&](int f, int i, auto&& visit) {
    const int a = faces[4 * f + i], b = faces[4 * f + ((i + 1) & 3)];
    for (int t = vc.start[std::size_t(a)]; t < vc.start[std::size_t(a) + 1]; ++t) {
      const int c = vc.corner[std::size_t(t)];
      const int g = c >> 2, j = c & 3;
      if (faces[4 * g + ((j + 1) & 3)] == b)
        visit(g, j);
      else if (faces[4 * g + ((j + 3) & 3)] == b)
        visit(g, (j + 3) & 3);
    }
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, F, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int f = r.begin(); f != r.end(); ++f)
      for (int i = 0; i < 4; ++i) {
        int best = -1, n = 0;
        for_each_incidence(f, i, [&](int g, int j) {
          ++n;
          if (best < 0) best = 4 * g + j;  // corners around a are in ascending face order
        });
        key[std::size_t(4 * f + i)] = best;
        count[std::size_t(4 * f + i)] = n;
      }
  });
  assign_on_huge_pages(el.corner_edge, std::size_t(F) * 4);
  std::vector<int> rep_of_edge;
  rep_of_edge.reserve(std::size_t(F) * 2 + 4);
  el.start.assign(1, 0);
  for (int c = 0; c < 4 * F; ++c)
    if (key[std::size_t(c)] == c) {
      el.corner_edge[std::size_t(c)] = int(rep_of_edge.size());
      rep_of_edge.push_back(c);
      el.start.push_back(el.start.back() + count[std::size_t(c)]);
    }
  for (int c = 0; c < 4 * F; ++c) el.corner_edge[std::size_t(c)] = el.corner_edge[std::size_t(key[std::size_t(c)])];
  const int E = int(rep_of_edge.size());
  int k = 0;
  for (int e = 0; e < E; ++e) k = std::max(k, 2 + 2 * (el.start[std::size_t(e) + 1] - el.start[std::size_t(e)]));
  if (k > 127) throw InputError("interpolated: an edge has too many incident faces");
  el.k = k;
  el.num_edges = E;
  const std::size_t total = std::size_t(el.start[std::size_t(E)]);
  assign_on_huge_pages(el.inc_face, total);
  assign_on_huge_pages(el.inc_local, total);
  assign_on_huge_pages(el.inc_slot, total * 4);
  assign_on_huge_pages(el.ids, std::size_t(E) * std::size_t(k));
  assign_on_huge_pages(el.size, std::size_t(E));
  tbb::parallel_for(tbb::blocked_range<int>(0, E, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int e = r.begin(); e != r.end(); ++e) {
      const int rep = rep_of_edge[std::size_t(e)];
      int a = el.start[std::size_t(e)];
      for_each_incidence(rep >> 2, rep & 3, [&](int g, int j) {
        el.inc_face[std::size_t(a)] = g;
        el.inc_local[std::size_t(a++)] = std::int8_t(j);
      });
      int* ids = el.ids.data() + std::size_t(e) * std::size_t(k);
      int used = 0;
      for (a = el.start[std::size_t(e)]; a < el.start[std::size_t(e) + 1]; ++a) {
        const int f = el.inc_face[std::size_t(a)];
        for (int j = 0; j < 4; ++j) {
          const int v = faces[4 * f + j];
          int s = 0;
          while (s < used && ids[s] != v) ++s;
          if (s == used) ids[used++] = v;
          el.inc_slot[std::size_t(a) * 4 + std::size_t(j)] = std::int8_t(s);
        }
      }
      el.size[std::size_t(e)] = std::uint8_t(used);
      for (int s = used; s < k; ++s) ids[s] = ids[0];
    }
  });
  return el;
}

// Per thread: vertex stamps (ColumnScratch) and edge stamps; the edges of the faces around v are
// listed in ascending order so the summation order is fixed.
struct ProjectionScratch {
  ColumnScratch col;
  std::vector<int> edge_stamp, edges;
  ProjectionScratch(int V, int E, std::size_t cap_n, std::size_t cap_e)
      : col(V, cap_n), edge_stamp(std::size_t(E), -1), edges(cap_e) {}
};

// Sorted edges of the faces around v into sc.edges; returns their count.
inline int projection_edges(const EdgeElements& el, const VertexCorners& vc, ProjectionScratch& sc, int v, int mark) {
  const int* fe = el.corner_edge.data();
  int ne = 0;
  for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
    const int* fe4 = fe + (vc.corner[std::size_t(a)] & ~3);
    for (int i = 0; i < 4; ++i)
      if (sc.edge_stamp[std::size_t(fe4[i])] != mark)
        sc.edge_stamp[std::size_t(fe4[i])] = mark, sc.edges[std::size_t(ne++)] = fe4[i];
  }
  std::sort(sc.edges.begin(), sc.edges.begin() + ne);
  return ne;
}

// Distinct vertices of the elements of the ne edges (unsorted, into sc.col.list); returns the count.
inline int projection_vertices(const EdgeElements& el, ProjectionScratch& sc, int ne, int mark) {
  int n = 0;
  int* stamp = sc.col.stamp.data();
  int* list = sc.col.list.data();
  for (int t = 0; t < ne; ++t) {
    const int* ids = el.ids.data() + std::size_t(sc.edges[std::size_t(t)]) * std::size_t(el.k);
    for (int s = 0; s < el.k; ++s)
      if (stamp[ids[s]] != mark) stamp[ids[s]] = mark, list[n++] = ids[s];
  }
  return n;
}

}  // namespace

std::unique_ptr<ProjectionPattern> build_projection_pattern(const int* faces, int F, const VertexCorners& vc) {
  auto p = std::make_unique<ProjectionPattern>();
  const EdgeElements el = build_edge_elements(faces, F, vc);
  const int V = int(vc.start.size()) - 1, E = el.num_edges, k = el.k;
  p->k = k;
  p->num_edges = E;
  assign_on_huge_pages(p->size, el.size.data(), el.size.data() + el.size.size());
  assign_on_huge_pages(p->inc_start, el.start.data(), el.start.data() + el.start.size());
  const std::size_t I = el.inc_face.size();
  // Pattern arrays are streamed by every assembly on this connectivity: huge pages from the start.
  assign_on_huge_pages(p->inc_row, I);
  assign_on_huge_pages(p->inc_coef, I);
  assign_on_huge_pages(p->inc_slot, I * 4);
  tbb::parallel_for(tbb::blocked_range<int>(0, E, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int e = r.begin(); e != r.end(); ++e) {
      const int a0 = el.start[std::size_t(e)], a1 = el.start[std::size_t(e) + 1];
      const double inv = 1.0 / double(a1 - a0);
      for (int a = a0; a < a1; ++a) {
        const int f = el.inc_face[std::size_t(a)], i = el.inc_local[std::size_t(a)];
        p->inc_row[std::size_t(a)] = 4 * f + i;
        // docs/math.md §0 edge sign: +1 if v_i < v_{i+1}.
        p->inc_coef[std::size_t(a)] = (faces[4 * f + i] < faces[4 * f + ((i + 1) & 3)] ? 1.0 : -1.0) * inv;
        for (int j = 0; j < 4; ++j)
          p->inc_slot[std::size_t(a) * 4 + std::size_t(j)] =
              std::uint8_t(el.inc_slot[std::size_t(a) * 4 + std::size_t(j)]);
      }
    }
  });
  const std::size_t cap_e = std::size_t(4 * vc.max_degree + 1), cap_n = cap_e * std::size_t(k) + 1;
  tbb::enumerable_thread_specific<ProjectionScratch> scratch([&] { return ProjectionScratch(V, E, cap_n, cap_e); });
  assign_on_huge_pages(p->outer, std::size_t(V) + 1);
  assign_on_huge_pages(p->ce_start, std::size_t(V) + 1);
  // Stamps (edge and vertex arrays): v in pass 1, V + v in pass 2, so nothing is ever reset.
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& range) {
    ProjectionScratch& sc = scratch.local();
    for (int v = range.begin(); v != range.end(); ++v) {
      const int ne = projection_edges(el, vc, sc, v, v);
      p->ce_start[std::size_t(v) + 1] = ne;
      p->outer[std::size_t(v) + 1] = projection_vertices(el, sc, ne, v);
    }
  });
  int widest = 0;
  for (int v = 0; v < V; ++v) {
    widest = std::max(widest, p->outer[std::size_t(v) + 1]);
    p->outer[std::size_t(v) + 1] += p->outer[std::size_t(v)];
    p->ce_start[std::size_t(v) + 1] += p->ce_start[std::size_t(v)];
  }
  p->wide = widest > 255;
  const std::size_t CE = std::size_t(p->ce_start[std::size_t(V)]);
  assign_on_huge_pages(p->inner, std::size_t(p->outer[std::size_t(V)]));
  assign_on_huge_pages(p->ce_edge, CE);
  assign_on_huge_pages(p->ce_sv, CE);
  if (p->wide) {
    assign_on_huge_pages(p->face_pos32, vc.corner.size() * 4);
    assign_on_huge_pages(p->ce_pos32, CE * std::size_t(k));
  } else {
    assign_on_huge_pages(p->face_pos8, vc.corner.size() * 4);
    assign_on_huge_pages(p->ce_pos8, CE * std::size_t(k));
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& range) {
    ProjectionScratch& sc = scratch.local();
    int* pos = sc.col.pos.data();
    auto put = [&](std::uint8_t* p8, int* p32, std::size_t idx, int value) {
      if (p32)
        p32[idx] = value;
      else
        p8[idx] = std::uint8_t(value);
    };
    for (int v = range.begin(); v != range.end(); ++v) {
      const int ne = projection_edges(el, vc, sc, v, V + v);
      const int n = projection_vertices(el, sc, ne, V + v);
      std::sort(sc.col.list.begin(), sc.col.list.begin() + n);
      std::copy_n(sc.col.list.begin(), n, p->inner.begin() + p->outer[std::size_t(v)]);
      for (int t = 0; t < n; ++t) pos[sc.col.list[std::size_t(t)]] = t;
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
        for (int j = 0; j < 4; ++j)
          put(p->face_pos8.data(), p->wide ? p->face_pos32.data() : nullptr, std::size_t(a) * 4 + std::size_t(j),
              pos[f[j]]);
      }
      std::size_t c = std::size_t(p->ce_start[std::size_t(v)]);
      for (int t = 0; t < ne; ++t, ++c) {
        const int e = sc.edges[std::size_t(t)];
        const int* ids = el.ids.data() + std::size_t(e) * std::size_t(k);
        int sv = 0;
        while (ids[sv] != v) ++sv;  // v is in the element of every edge of its faces
        p->ce_edge[c] = e;
        p->ce_sv[c] = std::uint8_t(sv);
        for (int s = 0; s < k; ++s)
          put(p->ce_pos8.data(), p->wide ? p->ce_pos32.data() : nullptr, c * std::size_t(k) + std::size_t(s),
              pos[ids[s]]);
      }
    }
  });
  return p;
}

std::size_t memory_bytes(const ProjectionPattern& p) {
  auto b = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return b(p.size) + b(p.inc_start) + b(p.inc_row) + b(p.inc_coef) + b(p.inc_slot) + b(p.outer) + b(p.inner) +
         b(p.face_pos8) + b(p.face_pos32) + b(p.ce_start) + b(p.ce_edge) + b(p.ce_sv) + b(p.ce_pos8) + b(p.ce_pos32);
}

}  // namespace corrlap::detail

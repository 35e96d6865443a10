// The assembly seam (discretizations/assembly/): the gather through a QuadPattern equals the direct
// per-column gather bit for bit, a pattern refuses another connectivity, every quad method gives the
// same bits with and without a pattern, the storage helpers (size_for_fill, huge pages) keep
// contents, and the parallel AssemblyPlan construction equals a sequential ordered sum.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/discretizations/assembly/detail/huge_pages.hpp>
#include <corrlap/discretizations/assembly/detail/quad_pattern_access.hpp>
#include <corrlap/discretizations/assembly/parallel_assembly.hpp>
#include <corrlap/discretizations/assembly/quad_pattern.hpp>
#include <corrlap/discretizations/quad_assembly.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <string>

#include "reference_support.hpp"

using namespace corrlap;
using namespace corrlap::test;

namespace {

// The gather pattern of a QuadPattern (the internals the methods use).
const detail::QuadVertexPattern& vertex_pattern(const QuadPattern& p) {
  return detail::QuadPatternAccess::impl(p).vertex;
}

bool same_bits(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && a.nonZeros() == b.nonZeros() &&
         std::memcmp(a.outerIndexPtr(), b.outerIndexPtr(), sizeof(int) * std::size_t(a.cols() + 1)) == 0 &&
         std::memcmp(a.innerIndexPtr(), b.innerIndexPtr(), sizeof(int) * std::size_t(a.nonZeros())) == 0 &&
         std::memcmp(a.valuePtr(), b.valuePtr(), sizeof(double) * std::size_t(a.nonZeros())) == 0;
}

// A non-symmetric-in-value but symmetric-pattern kernel with values that make summation order
// visible in the last bits (sums of numbers of very different magnitude).
void test_kernel(int f, int i, double* rows) {
  for (int j = 0; j < 4; ++j) {
    const double a = std::sin(1.0 + f * 0.37 + (i + j) * 1.3) * std::pow(10.0, (f + i + j) % 7);
    rows[j] = a;
    rows[4 + j] = 1.0 / (1.0 + f + i * j);
  }
}

}  // namespace

TEST_CASE("QuadPattern vertex gather is bitwise the direct gather on several meshes and thread counts") {
  for (double h : {0.3, 0.17, 0.09}) {
    INFO("h = " << h);
    const SphereCase s = sphere_case(h, Eigen::Vector3d(0.03, -0.011, 0.02));
    const detail::VertexCorners vc = detail::vertex_corners(s.mesh);
    Eigen::SparseMatrix<double> A0, B0;
    set_thread_count(1);
    detail::gather_quad_rows<2>(s.mesh, vc, test_kernel, {&A0, &B0});
    REQUIRE(A0.nonZeros() > 0);
    for (int t : {1, 2, 8}) {
      set_thread_count(t);
      const QuadPattern qp = QuadPattern::build(s.mesh);
      const detail::QuadVertexPattern& pat = vertex_pattern(qp);
      REQUIRE(pat.has_slots);
      Eigen::SparseMatrix<double> A, B;
      // two matrices, no finisher: the paired path (gather_quad_row_pairs)
      detail::gather_quad_rows<2>(pat, test_kernel, {&A, &B});
      INFO(t << " threads");
      CHECK(same_bits(A, A0));
      CHECK(same_bits(B, B0));
    }
  }
  set_thread_count(0);
}

TEST_CASE("two-matrix gather through the pattern falls back to the generic path for high-valence vertices") {
  // A fan of 40 quads around vertex 0: its column has 81 rows, more than the paired path's stack
  // column (kPairColumnMax = 64), so gather_quad_rows must take the generic path (which sums long
  // columns in place).
  constexpr int n = 40;
  SurfelMesh fan;
  fan.positions.resize(1 + 2 * n, 3);
  fan.positions.row(0) = Eigen::RowVector3d(0, 0, 0);
  fan.faces.resize(n, 4);
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n, b = 2 * M_PI * (k + 0.5) / n;
    fan.positions.row(1 + k) = Eigen::RowVector3d(std::cos(a), std::sin(a), 0);
    fan.positions.row(1 + n + k) = Eigen::RowVector3d(2 * std::cos(b), 2 * std::sin(b), 0.1);
    fan.faces.row(k) << 0, 1 + k, 1 + n + k, 1 + (k + 1) % n;
  }
  const detail::VertexCorners vc = detail::vertex_corners(fan);
  REQUIRE(4 * vc.max_degree + 1 > detail::kPairColumnMax);
  REQUIRE(1 + 2 * n > detail::kPairColumnMax);
  Eigen::SparseMatrix<double> A0, B0;
  detail::gather_quad_rows<2>(fan, vc, test_kernel, {&A0, &B0});
  const QuadPattern qp = QuadPattern::build(fan);
  REQUIRE(vertex_pattern(qp).has_slots);
  Eigen::SparseMatrix<double> A, B;
  detail::gather_quad_rows<2>(vertex_pattern(qp), test_kernel, {&A, &B});
  CHECK(A0.col(0).nonZeros() == 1 + 2 * n);
  CHECK(same_bits(A, A0));
  CHECK(same_bits(B, B0));
}

TEST_CASE("size_for_fill: fresh storage has 2 MiB of spare capacity, sufficient storage is kept") {
  Eigen::SparseMatrix<double> A;
  const Eigen::Index nnz = 3'000'000;  // 24 MB of values: above glibc's mmap threshold
  detail::size_for_fill(A, 1000, nnz);
  CHECK(A.rows() == 1000);
  CHECK(A.cols() == 1000);
  CHECK(A.data().size() == nnz);  // the outer index is the caller's to fill
  const Eigen::Index spare = (Eigen::Index(2) << 20) / Eigen::Index(sizeof(int));
  // At least the spare room, at most one more 2 MiB block of indices, and a capacity whose arrays
  // (with malloc's 16-byte header, in 4 KiB pages) are whole 2 MiB multiples.
  auto mapping_friendly = [&](Eigen::Index cap, Eigen::Index least) {
    CHECK(cap >= least);
    CHECK(cap < least + spare);
    CHECK((4 * cap + 2048) % (Eigen::Index(2) << 20) == 0);
  };
  mapping_friendly(A.data().allocatedSize(), nnz + spare);
  const double* values = A.valuePtr();
  const int* indices = A.innerIndexPtr();
  detail::size_for_fill(A, 900, nnz - 1000);  // fits: same storage (assemble_into refills it)
  CHECK(A.rows() == 900);
  CHECK(A.data().size() == nnz - 1000);
  CHECK(A.valuePtr() == values);
  CHECK(A.innerIndexPtr() == indices);
  detail::size_for_fill(A, 900, nnz + 2 * spare);  // does not fit: new storage, again with spare room
  CHECK(A.data().size() == nnz + 2 * spare);
  mapping_friendly(A.data().allocatedSize(), nnz + 3 * spare);
}

TEST_CASE("advise_huge_pages keeps the contents of the buffer and of its neighbours") {
  // The end blocks are collapsed into huge pages in place: whatever else lives in them (here the
  // unadvised parts of the same vector, written before the call) must survive, as must writes after.
  // 20 MiB - 4 KiB: with glibc on Linux a 2 MiB-aligned mapping of its own, so both end blocks of
  // the sub-range lie inside it and are really collapsed (elsewhere the calls just fail).
  const std::size_t n = ((std::size_t(20) << 20) - 4096) / sizeof(double);
  std::unique_ptr<double, decltype(&std::free)> buffer(static_cast<double*>(std::malloc(n * sizeof(double))),
                                                       &std::free);
  REQUIRE(buffer);
  double* all = buffer.get();
  for (std::size_t i = 0; i < n; ++i) all[i] = double(i) * 0.5 + 1.0;
  const std::size_t b = 123'457, e = n - 398'765;  // unaligned sub-range, ends 3 MB before the end
  advise_huge_pages(all + b, (e - b) * sizeof(double));
  bool kept = true;
  for (std::size_t i = 0; i < n; ++i) kept = kept && all[i] == double(i) * 0.5 + 1.0;
  CHECK(kept);
  for (std::size_t i = b; i < e; ++i) all[i] = -double(i);
  bool written = true;
  for (std::size_t i = 0; i < n; ++i)
    written = written && all[i] == (i >= b && i < e ? -double(i) : double(i) * 0.5 + 1.0);
  CHECK(written);
}

TEST_CASE("assign_on_huge_pages gives the same vector as assign") {
  std::vector<std::uint16_t> v(3, 9);
  assign_on_huge_pages(v, std::size_t(5'000'001), std::uint16_t(7));  // 10 MB: hinted
  CHECK(v.size() == 5'000'001);
  CHECK(std::size_t(std::count(v.begin(), v.end(), std::uint16_t(7))) == v.size());
  std::vector<int> source(3'000'000);
  for (std::size_t i = 0; i < source.size(); ++i) source[i] = int(i * 2654435761u >> 3);
  std::vector<int> copy;
  assign_on_huge_pages(copy, source.data(), source.data() + source.size());
  CHECK(copy == source);
  std::vector<double> small;
  assign_on_huge_pages(small, 10, 1.5);  // under 4 MiB: a plain vector
  CHECK(small == std::vector<double>(10, 1.5));
  assign_on_huge_pages(small, 0);
  CHECK(small.empty());
}

TEST_CASE("a QuadPattern refuses a mesh of another connectivity") {
  const SphereCase a = sphere_case(0.25), b = sphere_case(0.2);
  const QuadPattern pb = QuadPattern::build(b.mesh);
  CHECK(pb.num_vertices() == b.mesh.num_vertices());
  CHECK(pb.num_faces() == b.mesh.num_faces());
  CHECK(vertex_pattern(pb).outer.size() == std::size_t(b.mesh.num_vertices()) + 1);
  CHECK(pb.matches(b.mesh));
  CHECK_FALSE(pb.matches(a.mesh));
  // Same sizes, one face rotated: another connectivity.
  SurfelMesh c = b.mesh;
  const Eigen::RowVector4i f0 = c.faces.row(c.num_faces() - 1);
  c.faces.row(c.num_faces() - 1) << f0[1], f0[2], f0[3], f0[0];
  CHECK_FALSE(pb.matches(c));
  SurfelMesh moved = b.mesh;  // positions are not part of the connectivity
  moved.positions *= 1.5;
  CHECK(pb.matches(moved));
  for (const char* name : {"fem", "interpolated", "polydec", "projected-polydec", "vrm", "corrected-vrm"}) {
    INFO(name);
    const auto d = make_discretization(name);
    CHECK_THROWS_WITH_AS(d->assemble(a.mesh, a.normals, Config{}, pb),
                         doctest::Contains("the QuadPattern was built for another connectivity"), InputError);
    CHECK_THROWS_WITH_AS(d->assemble(c, b.normals, Config{}, pb), doctest::Contains("other face ids"), InputError);
    Operators out;
    CHECK_THROWS_AS(d->assemble_into(a.mesh, a.normals, Config{}, pb, out), InputError);
  }
  CHECK_THROWS_AS(QuadPattern::build(SurfelMesh{}), InputError);
}

TEST_CASE("every quad method gives the same bits with and without a QuadPattern") {
  const SphereCase a = sphere_case(0.17, Eigen::Vector3d(0.013, -0.02, 0.007));
  const SphereCase b = sphere_case(0.23);
  const std::vector<std::pair<std::string, std::string>> cases = {{"fem", ""},
                                                                  {"fem", "mass=lumped"},
                                                                  {"interpolated", ""},
                                                                  {"interpolated", "assembly=local"},
                                                                  {"polydec", ""},
                                                                  {"projected-polydec", ""},
                                                                  {"vrm", ""},
                                                                  {"corrected-vrm", ""},
                                                                  {"corrected-vrm", "mass=lumped"},
                                                                  {"cotan", ""},
                                                                  {"heat-kernel", ""}};
  for (int t : {1, 2}) {
    set_thread_count(t);
    const QuadPattern pa = QuadPattern::build(a.mesh), pb = QuadPattern::build(b.mesh);
    const QuadPattern pa_copy = pa;  // copies share the state
    for (const auto& test_case : cases) {
      // Named copies, not a structured binding: INFO captures them in a lambda (clang-14 refuses bindings).
      const std::string& name = test_case.first;
      const std::string& kv = test_case.second;
      INFO(name << " " << kv << ", " << t << " threads");
      const auto d = make_discretization(name);
      const Config params = kv.empty() ? Config{} : Config::from_key_values({kv});
      const Operators one_shot = d->assemble(a.mesh, a.normals, params);
      const Operators with = d->assemble(a.mesh, a.normals, params, pa);
      CHECK(same_bits(with.L, one_shot.L));
      CHECK(same_bits(with.M, one_shot.M));
      // Refill through the pattern after an assembly on another mesh into the same output.
      Operators reused;
      d->assemble_into(b.mesh, b.normals, params, pb, reused);
      d->assemble_into(a.mesh, a.normals, params, pa_copy, reused);
      CHECK(same_bits(reused.L, one_shot.L));
      CHECK(same_bits(reused.M, one_shot.M));
      d->assemble_into(a.mesh, a.normals, params, reused);  // no pattern
      CHECK(same_bits(reused.L, one_shot.L));
      CHECK(same_bits(reused.M, one_shot.M));
    }
    CHECK(pa.memory_bytes() > vertex_pattern(pa).slot.size() * sizeof(std::uint16_t));
  }
  set_thread_count(0);
}

TEST_CASE("AssemblyPlan gather is bitwise the sequential ordered sum, with and without edge signs") {
  std::mt19937 rng(7);
  const int n = 300, k = 4;
  const std::size_t E = 900;
  std::vector<int> ids(E * k);
  std::vector<std::int8_t> signs(E * k);
  std::uniform_int_distribution<int> pick(0, n - 1);
  for (std::size_t e = 0; e < E; ++e) {
    // distinct ids within an element, as in a mesh
    for (int j = 0; j < k; ++j) {
      int v;
      bool dup;
      do {
        v = pick(rng);
        dup = false;
        for (int i = 0; i < j; ++i) dup = dup || ids[e * k + i] == v;
      } while (dup);
      ids[e * k + j] = v;
      signs[e * k + j] = std::int8_t(rng() % 2 ? 1 : -1);
    }
  }
  std::vector<double> locals(E * k * k);
  std::uniform_real_distribution<double> val(-1.0, 1.0);
  for (double& x : locals) x = val(rng) * std::pow(10.0, int(rng() % 9));
  for (bool with_signs : {false, true}) {
    // Reference: entry (r, c) = sum over elements ascending, in the plan's documented order.
    std::map<std::pair<int, int>, double> ref;  // (col, row)
    for (std::size_t e = 0; e < E; ++e)
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
          const double s = with_signs ? double(signs[e * k + i]) * double(signs[e * k + j]) : 1.0;
          ref[{ids[e * k + j], ids[e * k + i]}] += s * locals[e * k * k + std::size_t(i) * k + j];
        }
    for (int t : {1, 2, 8}) {
      set_thread_count(t);
      const AssemblyPlan plan(ids.data(), E, k, n, with_signs ? signs.data() : nullptr);
      const Eigen::SparseMatrix<double> A = plan.gather(locals.data());
      INFO("signs " << with_signs << ", " << t << " threads");
      REQUIRE(std::size_t(A.nonZeros()) == ref.size());
      auto it = ref.begin();
      bool all = true;
      for (int c = 0; c < n; ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator a(A, c); a; ++a, ++it)
          all = all && it->first == std::make_pair(c, int(a.row())) &&
                std::memcmp(&it->second, &a.valueRef(), sizeof(double)) == 0;
      CHECK(all);
    }
  }
  set_thread_count(0);
}

TEST_CASE("parallel row-sum lumping is bitwise the sequential row_sum_lumped") {
  const SphereCase s = sphere_case(0.13, Eigen::Vector3d(0.02, 0.01, -0.03));
  const detail::VertexCorners vc = detail::vertex_corners(s.mesh);
  Eigen::SparseMatrix<double> A, B;
  detail::gather_quad_rows<2>(s.mesh, vc, test_kernel, {&A, &B});
  for (int t : {1, 2, 8}) {
    set_thread_count(t);
    INFO(t << " threads");
    CHECK(same_bits(detail::row_sum_diagonal_symmetric(A), row_sum_lumped(A)));
    CHECK(same_bits(detail::row_sum_diagonal_symmetric(B), row_sum_lumped(B)));
  }
  set_thread_count(0);
}

TEST_CASE("the column finish hook sees every finished column once, on both gather paths") {
  const SphereCase s = sphere_case(0.17);
  const detail::VertexCorners vc = detail::vertex_corners(s.mesh);
  Eigen::SparseMatrix<double> A0, B0;
  detail::gather_quad_rows<2>(s.mesh, vc, test_kernel, {&A0, &B0});
  auto negate_first = [](int, const auto& col, int n) {
    for (int t = 0; t < n; ++t) col[0][t] *= -1.0;
  };
  Eigen::SparseMatrix<double> A1, B1, A2, B2;
  detail::gather_quad_rows<2>(s.mesh, vc, test_kernel, {&A1, &B1}, negate_first);
  const QuadPattern qp = QuadPattern::build(s.mesh);
  REQUIRE(vertex_pattern(qp).has_slots);
  detail::gather_quad_rows<2>(vertex_pattern(qp), test_kernel, {&A2, &B2}, negate_first);
  Eigen::SparseMatrix<double> negA0 = A0;
  negA0 *= -1.0;
  CHECK(same_bits(A1, negA0));
  CHECK(same_bits(A2, negA0));
  CHECK(same_bits(B1, B0));
  CHECK(same_bits(B2, B0));
}

TEST_CASE("parallel mesh validation reports what SurfelMesh::validate reports") {
  const SphereCase s = sphere_case(0.3);
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(message([&] { validate_mesh(s.mesh, "m"); }) == "no error");
  SurfelMesh bad = s.mesh;
  const int F = bad.num_faces();
  bad.faces(F - 1, 2) = bad.num_vertices();   // out of range, late
  bad.faces(F / 2, 3) = bad.faces(F / 2, 0);  // duplicate corner, earlier
  CHECK(message([&] { validate_mesh(bad, "m"); }) == message([&] { bad.validate("m"); }));
  CHECK(message([&] { validate_mesh(bad, "m"); }).find("face " + std::to_string(F / 2)) != std::string::npos);
  SurfelMesh nan = s.mesh;
  nan.positions(nan.num_vertices() - 1, 1) = std::nan("");
  CHECK(message([&] { validate_mesh(nan, "m"); }) == message([&] { nan.validate("m"); }));
  CHECK(message([&] { validate_mesh(nan, "m"); }) != "no error");
}

TEST_CASE("AssemblyPlan reports the first out-of-range index in element order") {
  std::vector<int> ids(4000 * 4);
  for (std::size_t a = 0; a < ids.size(); ++a) ids[a] = int(a % 97);
  ids[3001 * 4 + 2] = 500;
  ids[2999 * 4 + 1] = -3;
  for (int t : {1, 2, 8}) {
    set_thread_count(t);
    try {
      AssemblyPlan plan(ids.data(), 4000, 4, 97);
      FAIL("no error");
    } catch (const InputError& e) {
      CHECK(std::string(e.what()) == "assembly: element 2999 refers to index -3 outside [0, 97)");
    }
  }
  set_thread_count(0);
}

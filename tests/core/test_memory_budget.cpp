// The memory budget (core/memory_budget.hpp): sizes parsed as the CLI's --max-memory takes them, and
// every input-driven allocation that checks it (voxel grid, surface extraction, readers) refused
// with the numbers before allocating. Each doctest case runs in its own process (ctest), so the
// process-wide budget set here does not leak into other tests; it is restored anyway.
#include <doctest/doctest.h>

#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/surface/extract_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <string>

#include "test_support.hpp"

using namespace corrlap;

namespace {
struct BudgetScope {
  explicit BudgetScope(std::uint64_t bytes) { set_memory_budget(bytes); }
  ~BudgetScope() { set_memory_budget(0); }
};
std::string message_of(const auto& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}
}  // namespace

TEST_CASE("memory sizes: K, M, G, T suffixes are powers of 1024, anything else is named") {
  CHECK(parse_memory_size("1000000") == 1000000u);
  CHECK(parse_memory_size("64k") == 64u * 1024u);
  CHECK(parse_memory_size("512M") == 512ull << 20);
  CHECK(parse_memory_size("8G") == 8ull << 30);
  CHECK(parse_memory_size("8 GB") == 8ull << 30);
  CHECK(parse_memory_size("1.5GiB") == 3ull << 29);
  CHECK(parse_memory_size("2T") == 2ull << 40);
  for (const char* bad : {"", "0", "-1", "abc", "8X", "8GX", "1e999", ".", "0.1"}) {
    CAPTURE(bad);
    CHECK_THROWS_WITH_AS(parse_memory_size(bad), doctest::Contains("memory size"), InputError);
  }
  CHECK(readable_bytes(3.0 * 1024 * 1024) == "3.0 MiB");
}

TEST_CASE("the default budget is the machine's memory, check_memory_budget names need, budget and remedy") {
  set_memory_budget(0);
  CHECK(memory_budget() == physical_memory_bytes());
  CHECK(physical_memory_bytes() > (std::uint64_t{64} << 20));
  CHECK_NOTHROW(check_memory_budget(1024.0, "a small thing"));
  const std::string m = message_of([] { check_memory_budget(1e30, "a huge thing", "ask for less"); });
  CHECK(m.find("a huge thing needs") != std::string::npos);
  CHECK(m.find("this machine's memory; max_memory sets it") != std::string::npos);
  CHECK(m.find("; ask for less") != std::string::npos);
  const BudgetScope scope(1 << 20);
  CHECK(memory_budget() == 1u << 20);
  const std::string n = message_of([] { check_memory_budget(std::nan(""), "an unknown amount"); });
  CHECK(n.find("more than the memory budget of 1.0 MiB (max_memory)") != std::string::npos);
  try {
    check_memory_budget(1e30, "a huge thing");
  } catch (const InputError& e) {
    CHECK(e.parameter() == "max_memory");  // the CLI adds its flag, --max-memory
  }
}

TEST_CASE("a voxel grid and a surface extraction beyond the budget are refused before allocating") {
  {
    const BudgetScope scope(1 << 20);  // 256^3 voxels are 2 MiB of bits
    const std::string m = message_of([] { VoxelGrid(Eigen::Vector3i::Zero(), Eigen::Vector3i::Constant(255), 1.0); });
    CHECK(m.find("voxel grid: a box of 256x256x256 voxels needs 2.0 MiB, more than the memory budget of 1.0 MiB") !=
          std::string::npos);
    CHECK(m.find("use a larger grid step or a smaller box") != std::string::npos);
  }
  // sphere1 at h = 0.02 in [-1.5, 1.5]^3: a 0.5 MiB grid, but about 47 000 surfels (~5 MiB of mesh).
  DigitizationParams p;
  p.h = 0.02;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  p.offset = 2;
  const VoxelGrid grid = digitize(make_implicit_shape("sphere1"), p);
  CHECK(grid.memory_bytes() < (std::size_t{1} << 20));
  {
    const BudgetScope scope(2 << 20);
    const std::string m = message_of([&] { extract_surface(grid); });
    CHECK(m.find("surface extraction of") != std::string::npos);
    CHECK(m.find("more than the memory budget of 2.0 MiB") != std::string::npos);
    CHECK(m.find("use a larger grid step h") != std::string::npos);
  }
  CHECK(extract_surface(grid).num_faces() > 40000);  // default budget: fine
}

TEST_CASE("readers check the memory budget before allocating what a header announces") {
  const BudgetScope scope(1 << 20);
  // A raw volume of 128^3 = 2 MiB announced, 8 bytes present: the budget is named first.
  const std::string raw = test::tmp_path("budget.raw");
  test::write_text(raw, "01234567");
  VolumeReadOptions opt;
  opt.raw_dimensions = Eigen::Vector3i::Constant(128);
  const std::string v = message_of([&] { read_volume(raw, opt); });
  CHECK(v.find("volume file '") != std::string::npos);
  CHECK(v.find("sizes 128 x 128 x 128 = 2 097 152 voxels needs 2.0 MiB, more than the memory budget of 1.0 MiB") !=
        std::string::npos);
  // Matrix Market: 50 000 entries present in the file, ~1.3 MiB of triplets and matrix.
  std::string mtx = "%%MatrixMarket matrix coordinate real general\n50000 50000 50000\n";
  for (int i = 1; i <= 50000; ++i) mtx += std::to_string(i) + " " + std::to_string(i) + " 1\n";
  const std::string path = test::tmp_path("budget.mtx");
  test::write_text(path, mtx);
  const std::string m = message_of([&] { read_matrix_market(path); });
  CHECK(m.find("Matrix Market file '") != std::string::npos);
  CHECK(m.find("50 000 entries needs") != std::string::npos);
  set_memory_budget(0);
  CHECK(read_matrix_market(path).nonZeros() == 50000);
}

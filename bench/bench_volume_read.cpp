// Reading a volume into voxels (goal: 512^3 and 1024^3 in seconds, bounded memory): the
// streamed read_volume_as_voxels against the bytes-then-threshold path it replaces,
// threshold_volume(read_volume(...)). The volume is a ball of radius 0.45 N, written once as a
// .vol Version 3 (zlib) file in the build's temporary directory.
//
//   ./build/bench/bench_volume_read --benchmark_filter=streamed/1024    (one path per process:
//   ./build/bench/bench_volume_read --benchmark_filter=bytes/1024        the peak RSS is the process's)
#include <benchmark/benchmark.h>

#include <corrlap/io/volume_io.hpp>
#include <filesystem>
#include <string>

#include "support.hpp"

using namespace corrlap;

namespace {
std::string ball_volume(int n) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("corrlap_bench_ball_" + std::to_string(n) + ".vol")).string();
  if (std::filesystem::exists(path)) return path;
  Volume v;
  v.size = Eigen::Vector3i::Constant(n);
  v.values.assign(std::size_t(n) * std::size_t(n) * std::size_t(n), 0);
  const double c = 0.5 * (n - 1), r2 = 0.45 * 0.45 * double(n) * double(n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        if ((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c) < r2)
          v.values[(std::size_t(z) * std::size_t(n) + std::size_t(y)) * std::size_t(n) + std::size_t(x)] = 255;
  VolumeWriteOptions o;
  o.compressed = nrrd_gzip_supported();
  write_volume(path, v, o);
  return path;
}
}  // namespace

// range(0): N (an N^3 volume).
static void BM_volume_read_streamed(benchmark::State& state) {
  const std::string path = ball_volume(int(state.range(0)));
  bench::reset_peak_rss();
  VolumeReadOptions o;
  o.inside = InsideRule::above(127);
  std::int64_t inside = 0;
  for (auto _ : state) inside = read_volume_as_voxels(path, o).count();
  state.counters["inside"] = double(inside);
  state.counters["file_MiB"] = double(std::filesystem::file_size(path)) / (1 << 20);
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
BENCHMARK(BM_volume_read_streamed)->Name("streamed")->Arg(512)->Arg(1024)->Unit(benchmark::kSecond);

static void BM_volume_read_bytes(benchmark::State& state) {
  const std::string path = ball_volume(int(state.range(0)));
  bench::reset_peak_rss();
  std::int64_t inside = 0;
  for (auto _ : state) inside = threshold_volume(read_volume(path), 127, 1.0).count();
  state.counters["inside"] = double(inside);
  state.counters["peak_rss_MiB"] = bench::peak_rss_mib();
}
BENCHMARK(BM_volume_read_bytes)->Name("bytes")->Arg(512)->Arg(1024)->Unit(benchmark::kSecond);

BENCHMARK_MAIN();

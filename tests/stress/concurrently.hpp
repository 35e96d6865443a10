#pragma once
// How the stress tests run their tasks at once.
//
// Normal builds: TBB tasks, the scheduler the library itself uses (and nests inside each task).
// ThreadSanitizer builds (CORRLAP_TSAN_STRESS, set by -DCORRLAP_TSAN=ON): one std::thread per lane,
// with TBB limited to the calling thread. Debian's libtbb.so is not instrumented, so TSan cannot
// see the synchronization of TBB's scheduler and reports every task hand-off and stack reuse as a
// race (692 reports in one run, none of them real). std::thread creation and join are
// instrumented: every report of such a run is a real race between concurrent corrlap calls.
// (Races inside one parallel loop are covered by the bitwise thread-count tests instead.)
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <thread>
#include <vector>

namespace corrlap::test {

#ifdef CORRLAP_TSAN_STRESS
/// TBB limited to the calling thread for the whole test program (the serial references too):
/// no TBB worker thread is ever started, so no uninstrumented hand-off can be misreported.
inline tbb::global_control serial_tbb_for_tsan(tbb::global_control::max_allowed_parallelism, 1);
#endif

/// Calls body(i) for every i in [0, n), up to `lanes` at once.
template <class Body>
void concurrently(int n, int lanes, Body&& body) {
#ifdef CORRLAP_TSAN_STRESS
  std::atomic<int> next{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < lanes; ++t)
    threads.emplace_back([&] {
      for (int i; (i = next++) < n;) body(i);
    });
  for (auto& thread : threads) thread.join();
#else
  // TBB caps workers at the core count by default; lift the cap and give the loop an arena of
  // `lanes` slots so that that many tasks really run at once.
  tbb::global_control allow(tbb::global_control::max_allowed_parallelism, std::size_t(lanes));
  tbb::task_arena arena(lanes);
  arena.execute([&] { tbb::parallel_for(0, n, 1, [&](int i) { body(i); }); });
#endif
}

}  // namespace corrlap::test

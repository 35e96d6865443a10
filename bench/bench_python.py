"""Overhead of the Python bindings: corrlap.laplacian(method="fem") end to end (array conversion,
assembly, scipy.sparse.csc_matrix out) against the bare C++ assembly of the same inputs, timed in
the same process by corrlap._core._time_fem_assembly. Results in bench/RESULTS.md ("Python overhead").

    PYTHONPATH=build/python python3 bench/bench_python.py [--h 0.005] [--repeat 7] [--threads 0]
Exits 1 when the overhead exceeds --limit (default 15 %). The overhead is taken from the best of
the interleaved runs: on a shared machine the medians move by tens of percent with the other
tenants' load, the best times do not (both are printed).
"""
import argparse
import statistics
import sys
import time

import corrlap
from corrlap import _core


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, default=0.005)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--threads", type=int, default=0, help="0: all cores")
    ap.add_argument("--limit", type=float, default=0.15)
    a = ap.parse_args()
    corrlap.set_threads(a.threads)
    V, F = corrlap.digitize("sphere1", h=a.h, bbox=(-1.5, 1.5))
    fn = corrlap.true_normals("sphere1", V, F)
    print(f"sphere1 h={a.h}: {len(V)} vertices, {len(F)} faces, {corrlap.get_threads()} threads")
    py, cpp = [], []
    corrlap.laplacian(V, F, method="fem", face_normals=fn)  # warm-up: first-touch of the allocator
    for _ in range(a.repeat):  # interleaved, so that drifts of a shared machine hit both alike
        t0 = time.perf_counter()
        L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)
        py.append(time.perf_counter() - t0)
        del L, M
        cpp.append(_core._time_fem_assembly(V, F, fn))
    mp, mc = statistics.median(py), statistics.median(cpp)
    overhead = min(py) / min(cpp) - 1
    print(f"{'':24s} {'median ms':>10s} {'min ms':>8s}")
    print(f"{'python laplacian(fem)':24s} {1e3 * mp:10.1f} {1e3 * min(py):8.1f}")
    print(f"{'C++ assembly':24s} {1e3 * mc:10.1f} {1e3 * min(cpp):8.1f}")
    print(f"overhead: {100 * overhead:+.1f} % of the best times (limit {100 * a.limit:.0f} %), "
          f"{100 * (mp / mc - 1):+.1f} % of the medians")
    return 0 if overhead <= a.limit else 1


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""mtxdiff.py A.mtx B.mtx TOL: compares two Matrix Market coordinate matrices.

Prints rel = max |A - B| / max |B| and the number of entries that are nonzero (above 1e-14 max |B|)
in one matrix only. Exits 0 when rel <= TOL and both have the same nonzero pattern, 1 otherwise.
Plain Python (no numpy); symmetric files are expanded.
"""
import sys


def load(path):
    entries = {}
    with open(path) as f:
        banner = f.readline().split()
        if not banner or banner[0] != "%%MatrixMarket":
            sys.exit(f"{path}: not a Matrix Market file")
        symmetric = len(banner) > 4 and banner[4].lower() == "symmetric"
        size = None
        for line in f:
            if line.startswith("%") or not line.strip():
                continue
            fields = line.split()
            if size is None:
                size = (int(fields[0]), int(fields[1]))
                continue
            i, j, v = int(fields[0]), int(fields[1]), float(fields[2])
            entries[(i, j)] = entries.get((i, j), 0.0) + v
            if symmetric and i != j:
                entries[(j, i)] = entries.get((j, i), 0.0) + v
    return size, entries


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    (size_a, a), (size_b, b) = load(sys.argv[1]), load(sys.argv[2])
    tol = float(sys.argv[3])
    if size_a != size_b:
        print(f"sizes differ: {size_a} vs {size_b}")
        sys.exit(1)
    scale = max((abs(v) for v in b.values()), default=0.0) or 1.0
    diff = max((abs(a.get(k, 0.0) - b.get(k, 0.0)) for k in a.keys() | b.keys()), default=0.0)
    rel = diff / scale

    def pattern(m):
        return {k for k, v in m.items() if abs(v) > 1e-14 * scale}

    only_a, only_b = len(pattern(a) - pattern(b)), len(pattern(b) - pattern(a))
    print(f"rel={rel:.3e} only_in_first={only_a} only_in_second={only_b}")
    sys.exit(0 if rel <= tol and only_a == 0 and only_b == 0 else 1)


if __name__ == "__main__":
    main()

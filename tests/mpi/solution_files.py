"""The solution files of the CLI tests under mpirun: one number per line (`corrlap solve --out`,
`corrlap eigs` on stdout), compared by their largest difference relative to the reference's
largest entry. Plain Python, no numpy: whatever python3 is first on PATH."""


def load(path):
    with open(path) as f:
        return [float(line) for line in f if line.strip() and not line.startswith("#")]


def relative_difference(a, b):
    """max |a - b| / max |b|, for lists of the same length (b the reference)."""
    assert len(a) == len(b), (len(a), len(b))
    return max(abs(x - y) for x, y in zip(a, b)) / max(abs(y) for y in b)

#!/usr/bin/python3
"""Probe: can the regularization's normal equations A p' = b, A = L M_l^-1 L + alpha M_l, be solved
by CG with a diagonal (Jacobi) preconditioner, without the factorization of B = sqrt(alpha) M_l - L
(regularization/laplacian_regularization.cpp)?

Reads L.mtx and M.mtx (`corrlap operators --volume V --method fem --out OPS`) and a `corrlap
regularize --no-render --out RUN` of the same volume (input.ply: positions, normals and H;
regularized.ply: the solution; metrics.json: alpha, h). Prints the Gershgorin bound of the
spectrum of M_l^-1 L, then runs Jacobi CG from the input positions and reports, every 100
iterations, the distance of the iterate to the solution (area-weighted RMS, worst coordinate, in
voxels).

    /usr/bin/python3 bench/jacobi_cg_probe.py OPS RUN [ITERATIONS]
"""
import json
import sys

import numpy as np
import scipy.io as sio


def read_ply(path):
    with open(path, "rb") as f:
        header = []
        while not header or header[-1] != "end_header":
            header.append(f.readline().decode().strip())
        count = int(next(line for line in header if line.startswith("element vertex")).split()[2])
        names = [line.split()[2] for line in header if line.startswith("property double")]
        data = np.frombuffer(f.read(count * 8 * len(names)), dtype="<f8").reshape(count, len(names))
    return {name: data[:, i] for i, name in enumerate(names)}


def main():
    ops, run = sys.argv[1], sys.argv[2]
    iterations = int(sys.argv[3]) if len(sys.argv) > 3 else 2000
    L = sio.mmread(f"{ops}/L.mtx").tocsr()
    m = np.asarray(sio.mmread(f"{ops}/M.mtx").sum(axis=1)).ravel()  # the lumped mass
    given, solved = read_ply(f"{run}/input.ply"), read_ply(f"{run}/regularized.ply")
    p = np.c_[given["x"], given["y"], given["z"]]
    n = np.c_[given["nx"], given["ny"], given["nz"]]
    solution = np.c_[solved["x"], solved["y"], solved["z"]]
    metrics = json.load(open(f"{run}/metrics.json"))
    alpha, h = metrics["alpha"], metrics["h"]
    b = alpha * m[:, None] * p - 2 * (L @ (given["H"][:, None] * n))

    def A(x):
        return L @ ((L @ x) / m[:, None]) + alpha * m[:, None] * x

    diagonal = np.asarray(L.multiply(L).T @ (1 / m)).ravel() + alpha * m
    area = m.sum()
    bound = np.max(np.asarray(abs(L).sum(axis=1)).ravel() / m)
    print(f"n {len(m)}, alpha {alpha:.6g}, Gershgorin bound of |M_l^-1 L| {bound:.3g} "
          f"({bound * h * h:.3g} in voxel units), (bound^2 + alpha) / alpha {(bound ** 2 + alpha) / alpha:.3g}")

    x = p.copy()
    r = b - A(x)
    z = r / diagonal[:, None]
    d = z.copy()
    rz = (r * z).sum(axis=0)
    for k in range(1, iterations + 1):
        Ad = A(d)
        step = rz / (d * Ad).sum(axis=0)
        x += step * d
        r -= step * Ad
        if k % 100 == 0 or k == iterations:
            error = np.sqrt((m[:, None] * (x - solution) ** 2).sum(axis=0).max() / area) / h
            print(f"iteration {k}: distance to the solution {error:.3g} voxels")
        z = r / diagonal[:, None]
        rz_next = (r * z).sum(axis=0)
        d = z + (rz_next / rz) * d
        rz = rz_next


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Probe: can the regularization's system be solved without factorizing anything?

A = L M_l^-1 L + alpha M_l factors over the complex numbers as conj(C) M_l^-1 C with
C = L - i s M_l, s = sqrt(alpha), and A^-1 = Im(C^-1) / s: one complex-symmetric solve C y = b gives
the positions x = Im(y) / s, with no squaring of the inner solve's error (unlike the real
preconditioner B^-1 M_l B^-1 of regularization/laplacian_regularization.cpp). This counts the
iterations of COCG (CG for complex-symmetric matrices) on C with a Jacobi preconditioner, and the
relative residual of x in A, on the operators of `corrlap operators --volume V --method fem --out DIR`.

    /usr/bin/python3 bench/complex_shift_probe.py DIR ALPHA
"""
import sys
import time

import numpy as np
import scipy.io as sio
import scipy.sparse as sp


def cocg(C, b, precondition, tolerance, max_iterations=5000):
    x = np.zeros(b.shape, dtype=complex)
    r = b.astype(complex)
    z = precondition(r)
    p = z.copy()
    rz = np.sum(r * z)
    norm_b = np.linalg.norm(b)
    for k in range(max_iterations):
        q = C @ p
        a = rz / np.sum(p * q)  # the unconjugated product: C is complex symmetric, not Hermitian
        x += a * p
        r -= a * q
        if np.linalg.norm(r) < tolerance * norm_b:
            return x, k + 1
        z = precondition(r)
        rz_next = np.sum(r * z)
        p = z + (rz_next / rz) * p
        rz = rz_next
    return x, max_iterations


def main():
    folder, alpha = sys.argv[1], float(sys.argv[2])
    L = sio.mmread(folder + "/L.mtx").tocsr()
    mass = np.asarray(sio.mmread(folder + "/M.mtx").tocsr().sum(axis=1)).ravel()
    n, s = L.shape[0], np.sqrt(alpha)
    C = (L - 1j * s * sp.diags(mass)).tocsr()
    diagonal = C.diagonal()
    rng = np.random.default_rng(0)
    print(f"{n} unknowns, alpha {alpha}")
    for name, b in [("random", rng.standard_normal(n)), ("smooth", mass * np.sin(np.arange(n) / n * 20))]:
        for tolerance in [1e-4, 1e-6, 1e-8]:
            start = time.time()
            y, iterations = cocg(C, b, lambda r: r / diagonal, tolerance)
            x = y.imag / s
            residual = b - (L @ ((L @ x) / mass) + alpha * mass * x)
            print(f"{name} rhs, COCG to {tolerance:g}: {iterations} iterations, relative residual in A "
                  f"{np.linalg.norm(residual) / np.linalg.norm(b):.2e}, {time.time() - start:.1f} s")


if __name__ == "__main__":
    main()

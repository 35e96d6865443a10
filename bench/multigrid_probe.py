#!/usr/bin/python3
"""Probe: can a smoothed-aggregation V-cycle replace the factorization of B = sqrt(alpha) M_l - L in
the regularization's preconditioned CG (regularization/laplacian_regularization.cpp)?

Reads L.mtx and M.mtx (`corrlap operators --volume V --method fem --out DIR`), builds a plain
smoothed-aggregation hierarchy on B (all off-diagonal entries strong, greedy aggregation, one
damped-Jacobi smoothing of the tentative prolongator, Galerkin coarse operators, the coarsest level
factorized; Chebyshev smoothing of degree 2 before and after), and counts iterations:
  - CG on B preconditioned by one V-cycle, to a relative residual of 1e-10;
  - the regularization's outer CG on A = L M_l^-1 L + alpha M_l to 1e-8, with the exact
    preconditioner B^-1 M_l B^-1 replaced by V M_l V (one or two V-cycles for each B^-1).
Iteration counts, not times, are what carry over to C++.

    /usr/bin/python3 bench/multigrid_probe.py DIR ALPHA
"""
import sys
import time

import numpy as np
import scipy.io as sio
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def aggregates(A):
    """Greedy aggregation over the off-diagonal pattern: a node whose neighbours are all free
    starts an aggregate with them; the rest join a neighbouring aggregate."""
    A = A.tocsr()
    n = A.shape[0]
    agg = -np.ones(n, dtype=np.int64)
    k = 0
    for i in range(n):
        if agg[i] >= 0:
            continue
        nb = A.indices[A.indptr[i]:A.indptr[i + 1]]
        if (agg[nb] < 0).all():
            agg[nb] = k
            agg[i] = k
            k += 1
    for i in np.where(agg < 0)[0]:
        nb = A.indices[A.indptr[i]:A.indptr[i + 1]]
        taken = agg[nb][agg[nb] >= 0]
        agg[i] = taken[0] if len(taken) else k
        k += 0 if len(taken) else 1
    return agg, k


def spectral_radius(A, inverse_diagonal, iterations=15):
    x = np.random.default_rng(0).standard_normal(A.shape[0])
    value = 0.0
    for _ in range(iterations):
        y = inverse_diagonal * (A @ x)
        value = np.linalg.norm(y) / np.linalg.norm(x)
        x = y / np.linalg.norm(y)
    return value


class Hierarchy:
    def __init__(self, A, coarsest=4000):
        self.levels = []
        while True:
            level = {"A": A, "Dinv": 1.0 / A.diagonal()}
            level["rho"] = spectral_radius(A, level["Dinv"])
            self.levels.append(level)
            if A.shape[0] <= coarsest:
                level["lu"] = spla.splu(A.tocsc())
                break
            agg, k = aggregates(A)
            n = A.shape[0]
            P0 = sp.csr_matrix((np.ones(n), (np.arange(n), agg)), shape=(n, k))
            P0 = P0 @ sp.diags(1.0 / np.sqrt(np.asarray(P0.sum(axis=0)).ravel()))
            omega = 4.0 / 3.0 / level["rho"]
            P = (P0 - omega * sp.diags(level["Dinv"]) @ (A @ P0)).tocsr()
            level["P"], level["R"] = P, P.T.tocsr()
            A = (level["R"] @ A @ P).tocsr()

    def smooth(self, level, b, x, degree=2):
        """Chebyshev iteration on D^-1 A over [rho / 30, 1.1 rho]."""
        high = 1.1 * level["rho"]
        low = high / 30.0
        theta, delta = 0.5 * (high + low), 0.5 * (high - low)
        sigma = theta / delta
        rho_k = 1.0 / sigma
        r = b - level["A"] @ x
        d = level["Dinv"] * r / theta
        for _ in range(degree):
            x = x + d
            r = r - level["A"] @ d
            rho_next = 1.0 / (2.0 * sigma - rho_k)
            d = rho_next * rho_k * d + 2.0 * rho_next / delta * (level["Dinv"] * r)
            rho_k = rho_next
        return x

    def vcycle(self, b, index=0):
        level = self.levels[index]
        if "lu" in level:
            return level["lu"].solve(b)
        x = self.smooth(level, b, np.zeros_like(b))
        x = x + level["P"] @ self.vcycle(level["R"] @ (b - level["A"] @ x), index + 1)
        return self.smooth(level, b, x)


def main():
    folder, alpha = sys.argv[1], float(sys.argv[2])
    L = sp.csr_matrix(sio.mmread(folder + "/L.mtx"))
    M = sp.csr_matrix(sio.mmread(folder + "/M.mtx"))
    mass = np.asarray(M.sum(axis=1)).ravel()
    B = (sp.diags(np.sqrt(alpha) * mass) - L).tocsr()
    n = B.shape[0]
    start = time.time()
    h = Hierarchy(B)
    sizes = [level["A"].shape[0] for level in h.levels]
    complexity = sum(level["A"].nnz for level in h.levels) / B.nnz
    print(f"hierarchy: sizes {sizes}, operator complexity {complexity:.2f} ({time.time() - start:.1f} s in Python)")
    count = [0]

    def counted(_):
        count[0] += 1

    rng = np.random.default_rng(1)
    b = rng.standard_normal(n)
    V = spla.LinearOperator(B.shape, matvec=h.vcycle)
    x, _ = spla.cg(B, b, tol=1e-10, atol=0, M=V, callback=counted)
    print(f"CG on B, one V-cycle: {count[0]} iterations, relative residual "
          f"{np.linalg.norm(b - B @ x) / np.linalg.norm(b):.1e}")
    A = spla.LinearOperator(B.shape, matvec=lambda x: L @ ((L @ x) / mass) + alpha * mass * x)

    def two_cycles(r):
        x1 = h.vcycle(r)
        return x1 + h.vcycle(r - B @ x1)

    rhs = rng.standard_normal(n) * mass
    for name, inverse in (("one V-cycle", h.vcycle), ("two V-cycles", two_cycles)):
        count[0] = 0
        P = spla.LinearOperator(B.shape, matvec=lambda r: inverse(mass * inverse(r)))
        spla.cg(A, rhs, tol=1e-8, atol=0, M=P, callback=counted)
        print(f"outer CG on A, B^-1 by {name}: {count[0]} iterations")


if __name__ == "__main__":
    main()

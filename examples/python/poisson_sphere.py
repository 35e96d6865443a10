"""Poisson problem on the digitized unit sphere from Python (docs/math.md 10.4), the counterpart of
examples/poisson_sphere.cpp: voxels -> surface -> true normals -> corrected FEM -> L g = M b with
CHOLMOD, b = Laplacian of f = x^2 on the sphere (2 - 6 x^2); prints the errors.

    PYTHONPATH=build/python python3 examples/python/poisson_sphere.py
"""
import sys

import numpy as np

import corrlap

V, F = corrlap.digitize("sphere1", h=0.1, bbox=(-1.5, 1.5))
fn = corrlap.true_normals("sphere1", V, F)                    # (#F, 3)
L, M = corrlap.laplacian(V, F, method="fem", face_normals=fn)  # #V by #V, L negative semi-definite

q = V / np.linalg.norm(V, axis=1, keepdims=True)  # samples at the vertices' projections onto the sphere
f = q[:, 0] ** 2
b = 2 - 6 * q[:, 0] ** 2                          # Delta f
area = M.sum()
b -= (M @ b).sum() / area                         # compatible with the constant kernel of L

# Pin g[0] = f[0] and solve the free rows: -L_ff g_f = -(M b - L e_0 f[0])_f, SPD.
free = np.arange(1, len(V))
rhs = M @ b - L[:, 0].toarray().ravel() * f[0]
g = np.empty(len(V))
g[0] = f[0]
g[free] = corrlap.solve(-L[free][:, free], -rhs[free], solver="cholmod", positions=V[free])

mean = lambda u: (M @ u).sum() / area  # noqa: E731
e = (g - mean(g)) - (f - mean(f))
linf, l2 = np.abs(e).max(), np.sqrt(e @ (M @ e) / area)
print(f"{len(V)} vertices: error L_inf {linf:.4g}, L2 {l2:.4g}")
sys.exit(0 if linf < 0.03 and l2 < 0.01 else 1)

#!/usr/bin/python3
"""Probes (not features): how much of corrlap regularize's distance to the truth comes from its
mean curvature H, on the inputs of bench/compare_surfaces.py (its voxelization, grid shifts and
measures). Every solve is the regularization's normal equations,
    (L M_l^-1 L + alpha M_l) p' = alpha M_l p - 2 L (H n),   alpha = alpha0 / (h s)^2,
on the staircase p with fem's L and M, solved by scipy; pass 1 is corrlap.regularize with the
CLI's defaults for a volume (II normals of 4 voxels, curvature ball max(0.1 s, 2 voxels)) at
alpha0 = 10, which the analytic shapes keep.

    /usr/bin/python3 bench/curvature_probe.py floor N SHAPES ALPHA0...
        pass 1, then the true H (at the vertices' projections onto the shape) with the II normals,
        and with the true normals too, at each ALPHA0
    /usr/bin/python3 bench/curvature_probe.py second-pass N SHAPES R:ALPHA0...
        pass 1, then a second solve with H estimated on pass 1's result (corrlap.curvature, ball
        of R voxels, pass 1's quad normals) and those normals in L, M
    /usr/bin/python3 bench/curvature_probe.py passes N SHAPES R COUNT
        pass 1, then COUNT more solves, each with H estimated on the last result (ball of R
        voxels, its quad normals) and L, M of pass 1 (which a solver could keep factorized)
    /usr/bin/python3 bench/curvature_probe.py ii N SHAPES R...
        pass 1, then a second solve with the integral-invariant mean curvature
        H = 8 / (3 R) - 4 V / (pi R^4) (V: the voxels' volume in a ball of R voxels, counted by
        voxel centres) in balls centred on pass 1's result (on the staircase's own vertices, half
        a voxel off the surface, V is off by about pi R^2 / 2)
    /usr/bin/python3 bench/curvature_probe.py bands N SHAPE
        the RMS error of H relative to the mean |H|, after 0, 4, 16 and 64 rounds of one-ring
        averaging (the error left at longer wavelengths), for H of the staircase and of pass 1
        in several balls (first grid shift only)

SHAPES: comma-separated names of compare_surfaces' shapes. floor, second-pass, passes and ii print
the mean distance to the truth in voxels averaged over the 3 grid shifts."""
import os
import sys

import numpy as np
import scipy.ndimage as ndi
import scipy.signal as signal
import scipy.sparse as sp
import scipy.sparse.linalg as sla

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "build", "python"))
import corrlap  # noqa: E402
import compare_surfaces as cs  # noqa: E402
import surface_truth as st  # noqa: E402

cs.st = st


def quad_normals(P, F):
    n = np.cross(P[F[:, 2]] - P[F[:, 0]], P[F[:, 3]] - P[F[:, 1]])
    return n / np.linalg.norm(n, axis=1)[:, None]


def vertex_normals(face_normals, F, count):
    s = np.zeros((count, 3))
    for j in range(4):
        np.add.at(s, F[:, j], face_normals)
    return s / np.linalg.norm(s, axis=1)[:, None]


class Input:
    """One voxelized shape: the staircase in corrlap's world units, its II normals, pass 1, the map
    to the truth's coordinates and the truth's H at the vertices."""

    def __init__(self, name, voxels, k, shift):
        work = os.path.join("curvature_probe_work", "%s_%d_s%d" % (name, voxels, k))
        os.makedirs(work, exist_ok=True)
        volume = os.path.join(work, "volume.npy")
        self.shape = st.SHAPES[name]
        h, origin, self.measure = cs.prepare_input(name, voxels, shift, volume, "")
        a = np.load(volume)
        self.step = 2.0 / max(a.shape)  # the world step of digitize_volume
        centre = (np.array(a.shape) - 1) / 2.0
        self.volume, self.centre = a, centre
        self.to_truth = lambda P: origin + h * (P / self.step + centre)
        self.V, self.F = corrlap.digitize_volume(a, threshold=0)
        self.tris = np.vstack([self.F[:, [0, 1, 2]], self.F[:, [0, 2, 3]]])
        self.nf = corrlap.ii_normals(a, self.V, self.F, threshold=0)
        self.size = 0.5 * (self.V.max(0) - self.V.min(0)).max()
        self.P1 = corrlap.regularize(self.V, self.F, face_normals=self.nf, h=self.step, alpha0=10,
                                     curvature_radius=max(0.1 * self.size, 2 * self.step))
        foot = st.project(self.shape, self.to_truth(self.V))[0]
        self.true_H = st.true_mean_curvature(self.shape, foot) * (h / self.step)  # in world units
        self.true_normals = st.true_normal(self.shape, foot)
        centres = st.project(self.shape, self.to_truth(self.V[self.F].mean(axis=1)))[0]
        self.true_face_normals = st.true_normal(self.shape, centres)

    def distance(self, P):
        return self.measure(self.to_truth(P), self.tris)["mean_dist_vox"]

    def solve(self, face_normals, H, alpha0):
        L, M = corrlap.laplacian(self.V, self.F, method="fem", face_normals=face_normals, h=self.step)
        L = sp.csc_matrix(L)
        m = np.asarray(sp.csr_matrix(M).sum(axis=1)).ravel()
        alpha = alpha0 / (self.step * self.size) ** 2
        A = (L @ sp.diags(1.0 / m) @ L + alpha * sp.diags(m)).tocsc()
        n = vertex_normals(face_normals, self.F, len(self.V))
        return sla.splu(A).solve(alpha * (m[:, None] * self.V) - 2.0 * (L @ (H[:, None] * n)))

    def pass1_normals(self):
        n = quad_normals(self.P1, self.F)
        return -n if np.mean(np.sum(n * self.nf, axis=1)) < 0 else n


def inputs(voxels, shapes):
    shift_args = type("Args", (), {"shift": None, "shifts": 3, "seed": 1})()
    for name in shapes:
        for k, shift in enumerate(cs.grid_shifts(shift_args)):
            yield name, Input(name, voxels, k, shift)


def table(shapes, keys, results):
    print("| input | " + " | ".join(keys) + " |")
    print("|---" * (len(keys) + 1) + "|")
    for name in shapes:
        print("| %s | " % name + " | ".join("%.4f" % np.mean(results[(name, key)]) for key in keys) + " |")


def floor(voxels, shapes, alphas):
    results, keys = {}, ["default"]
    for a in alphas:
        keys += ["true H, alpha0 %g" % a, "true H and n, alpha0 %g" % a]
    for name, x in inputs(voxels, shapes):
        row = {"default": x.distance(x.P1)}
        for a in alphas:
            row["true H, alpha0 %g" % a] = x.distance(x.solve(x.nf, x.true_H, a))
            row["true H and n, alpha0 %g" % a] = x.distance(x.solve(x.true_face_normals, x.true_H, a))
        for key, value in row.items():
            results.setdefault((name, key), []).append(value)
    table(shapes, keys, results)


def second_pass(voxels, shapes, variants):
    results, keys = {}, ["pass 1"] + variants
    for name, x in inputs(voxels, shapes):
        row = {"pass 1": x.distance(x.P1)}
        n2 = x.pass1_normals()
        for variant in variants:
            radius, alpha0 = (float(v) for v in variant.split(":"))
            H2 = corrlap.curvature(x.P1, x.F, face_normals=n2, radius=radius * x.step)[0]
            row[variant] = x.distance(x.solve(n2, H2, alpha0))
        for key, value in row.items():
            results.setdefault((name, key), []).append(value)
    table(shapes, keys, results)


def passes(voxels, shapes, radius, count):
    results, keys = {}, ["pass %d" % (k + 1) for k in range(count + 1)]
    for name, x in inputs(voxels, shapes):
        P, row = x.P1, [x.distance(x.P1)]
        for _ in range(count):
            n = quad_normals(P, x.F)
            if np.mean(np.sum(n * x.nf, axis=1)) < 0:
                n = -n
            H = corrlap.curvature(P, x.F, face_normals=n, radius=radius * x.step)[0]
            P = x.solve(x.nf, H, 10.0)
            row.append(x.distance(P))
        for key, value in zip(keys, row):
            results.setdefault((name, key), []).append(value)
    table(shapes, keys, results)


def integral_invariant(voxels, shapes, radii):
    results, keys = {}, ["pass 1"] + ["ii %g" % r for r in radii]
    for name, x in inputs(voxels, shapes):
        row = {"pass 1": x.distance(x.P1)}
        centres = (x.P1 / x.step + x.centre).T  # voxel index coordinates
        for radius in radii:
            r = int(np.ceil(radius))
            g = np.arange(-r, r + 1)
            ball = (g[:, None, None] ** 2 + g[None, :, None] ** 2 + g[None, None, :] ** 2 <= radius ** 2).astype(float)
            count = signal.fftconvolve(x.volume.astype(float), ball, mode="same")
            V = ndi.map_coordinates(count, centres, order=1)
            H = (8.0 / (3.0 * radius) - 4.0 * V / (np.pi * radius ** 4)) / x.step
            row["ii %g" % radius] = x.distance(x.solve(x.nf, H, 10.0))
        for key, value in row.items():
            results.setdefault((name, key), []).append(value)
    table(shapes, keys, results)


def bands(voxels, name):
    x = next(inputs(voxels, [name]))[1]
    n = len(x.V)
    i = np.concatenate([x.F[:, k] for k in range(4)] + [x.F[:, (k + 1) % 4] for k in range(4)])
    j = np.concatenate([x.F[:, (k + 1) % 4] for k in range(4)] + [x.F[:, k] for k in range(4)])
    W = sp.csr_matrix((np.ones(len(i)), (i, j)), shape=(n, n)) + sp.identity(n)
    W = sp.diags(1.0 / np.asarray(W.sum(axis=1)).ravel()) @ W
    scale = np.mean(np.abs(x.true_H))

    def errors(H):
        e, done, out = H - x.true_H, 0, []
        for rounds in (0, 4, 16, 64):
            while done < rounds:
                e, done = W @ e, done + 1
            out.append("%.4f" % (np.sqrt(np.mean(e ** 2)) / scale))
        return " | ".join(out)

    print("| H | ball (voxels) | 0 rounds | 4 | 16 | 64 |")
    print("|---|---|---|---|---|---|")
    for radius in (2, 3.2, 5, 8):
        H = corrlap.curvature(x.V, x.F, face_normals=x.nf, radius=radius * x.step)[0]
        print("| staircase, II normals | %g | %s |" % (radius, errors(H)))
    n2 = x.pass1_normals()
    for radius in (1, 2, 3.2, 5):
        H = corrlap.curvature(x.P1, x.F, face_normals=n2, radius=radius * x.step)[0]
        print("| pass 1's result | %g | %s |" % (radius, errors(H)))


def main():
    if len(sys.argv) < 4 or sys.argv[1] not in ("floor", "second-pass", "passes", "ii", "bands"):
        print(__doc__)
        return 2
    mode, voxels = sys.argv[1], int(sys.argv[2])
    if mode == "bands":
        bands(voxels, sys.argv[3])
    elif mode == "ii":
        integral_invariant(voxels, sys.argv[3].split(","), [float(r) for r in sys.argv[4:]])
    elif mode == "passes":
        passes(voxels, sys.argv[3].split(","), float(sys.argv[4]), int(sys.argv[5]))
    elif mode == "floor":
        floor(voxels, sys.argv[3].split(","), [float(a) for a in sys.argv[4:]] or [10.0])
    else:
        second_pass(voxels, sys.argv[3].split(","), sys.argv[4:])
    return 0


if __name__ == "__main__":
    sys.exit(main())

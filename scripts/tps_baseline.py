#!/usr/bin/env python3
"""The surface issue's baseline anyone can compute: a thin-plate-spline height field through the true curve
points of a simulated recording (SciPy's RBFInterpolator over the curves' best-fit plane), written as an OBJ
grid mesh over the boundary polygon, to be measured with `fires mesh compare OBJ --truth REC` like any surface.

usage: tps_baseline.py REC_DIR OUT.obj [--spacing-mm 1.0] [--max-points 3000]
Needs numpy and scipy (a venv; never a project dependency).
"""
import argparse
import json
import os

import numpy as np
from scipy.interpolate import RBFInterpolator


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rec")
    ap.add_argument("out")
    ap.add_argument("--spacing-mm", type=float, default=1.0)
    ap.add_argument("--max-points", type=int, default=3000)
    a = ap.parse_args()
    strokes = json.load(open(os.path.join(a.rec, "truth", "strokes.json")))
    curves = [np.array(s["tip_polyline_m"]) for s in strokes if s["complete"]]
    boundary = next(np.array(s["tip_polyline_m"]) for s in strokes if s["kind"] == "boundary")
    pts = np.vstack(curves)
    # Best-fit plane of the curve points.
    c = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - c, full_matrices=False)
    e1, e2, n = vt[0], vt[1], vt[2]
    uv = np.c_[(pts - c) @ e1, (pts - c) @ e2]
    h = (pts - c) @ n
    # Subsample evenly so the dense system stays small (the curves are sampled every 10 ms of drawing).
    step = max(1, len(pts) // a.max_points)
    uv_s, h_s = uv[::step], h[::step]
    # One sample per 0.1 mm cell: curves meet at junctions and the pen starts each stroke from rest,
    # and repeated points make the interpolation system singular.
    _, keep = np.unique(np.round(uv_s / 1e-4), axis=0, return_index=True)
    keep.sort()
    uv_s, h_s = uv_s[keep], h_s[keep]
    rbf = RBFInterpolator(uv_s, h_s, kernel="thin_plate_spline")
    # Grid over the boundary polygon (projected), even-odd inside test.
    buv = np.c_[(boundary - c) @ e1, (boundary - c) @ e2]
    s = a.spacing_mm * 1e-3
    lo, hi = buv.min(axis=0), buv.max(axis=0)
    us = np.arange(lo[0], hi[0] + s, s)
    vs = np.arange(lo[1], hi[1] + s, s)
    U, V = np.meshgrid(us, vs, indexing="ij")
    q = np.c_[U.ravel(), V.ravel()]
    inside = np.zeros(len(q), dtype=bool)
    x0, y0 = buv[:, 0], buv[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    for k in range(len(buv)):
        cond = (y0[k] > q[:, 1]) != (y1[k] > q[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = x0[k] + (q[:, 1] - y0[k]) * (x1[k] - x0[k]) / (y1[k] - y0[k])
        inside ^= cond & (q[:, 0] < xc)
    inside = inside.reshape(U.shape)
    H = rbf(q).reshape(U.shape)
    P = c + U[..., None] * e1 + V[..., None] * e2 + H[..., None] * n
    idx = -np.ones(U.shape, dtype=int)
    lines, k = [], 0
    for i in range(U.shape[0]):
        for j in range(U.shape[1]):
            if inside[i, j]:
                idx[i, j] = k
                k += 1
                lines.append("v %.9f %.9f %.9f" % tuple(P[i, j]))
    for i in range(U.shape[0] - 1):
        for j in range(U.shape[1] - 1):
            quad = [idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]]
            if min(quad) >= 0:
                lines.append("f %d %d %d %d" % tuple(x + 1 for x in quad))
    open(a.out, "w").write("\n".join(lines) + "\n")
    print(json.dumps({"points": int(len(uv_s)), "vertices": k}))


if __name__ == "__main__":
    main()

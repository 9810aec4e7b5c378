#!/usr/bin/env python3
"""Scan fitting compared in one run (issue 20): vclay fit, SciPy's FITPACK least-squares
B-spline (LSQBivariateSpline, a height field z(x, y)) and geomdl's approximate_surface (grid
data only), at an equal number of control points (32 x 32 bicubic), on the same clouds.

The error of every method is measured the same way: the RMS and maximum of the true
closest-point distances from the points to the fitted surface (vclay computes its own by
Newton; for SciPy and geomdl this script runs vectorized Gauss-Newton on the foot points with
finite-difference derivatives). Time: the fit alone (vclay: the report's `total`, which
excludes reading the file; SciPy and geomdl: the call).

Usage: compare_fit.py VCLAY DATA_DIR [CLOUD.ply ...]   (clouds from bench/get_scan.py; all of
them unless named)."""

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

GRID = 32
DEG = 3


def closest(eval_fn, u, v, pts, lo, hi, iters=8):
    """Gauss-Newton on |S(u, v) - p|^2 for all points at once; returns the distances."""
    h = 1e-6 * (hi - lo)
    for _ in range(iters):
        s = eval_fn(u, v)
        su = (eval_fn(u + h[0], v) - eval_fn(u - h[0], v)) / (2 * h[0])
        sv = (eval_fn(u, v + h[1]) - eval_fn(u, v - h[1])) / (2 * h[1])
        r = s - pts
        a11, a12, a22 = (su * su).sum(1), (su * sv).sum(1), (sv * sv).sum(1)
        g1, g2 = (su * r).sum(1), (sv * r).sum(1)
        det = a11 * a22 - a12 * a12
        det[det == 0] = 1.0
        u = np.clip(u - (a22 * g1 - a12 * g2) / det, lo[0], hi[0])
        v = np.clip(v - (a11 * g2 - a12 * g1) / det, lo[1], hi[1])
    d = np.linalg.norm(eval_fn(u, v) - pts, axis=1)
    return d


def stats(d):
    return {"rms": float(np.sqrt((d**2).mean())), "max": float(d.max())}


def read_ply(path):
    with open(path, "rb") as f:
        n = 0
        while True:
            line = f.readline().decode()
            if line.startswith("element vertex"):
                n = int(line.split()[2])
            if line.strip() == "end_header":
                break
        return np.frombuffer(f.read(24 * n), dtype="<f8").reshape(n, 3).copy()


def wave_truth(x, y):
    return 0.15 * np.sin(2 * x) * np.cos(1.5 * y)


def truth_rms(xyz):
    """RMS vertical deviation from the true wave of surface points inside the scanned region
    (away from the edge and the hole): the accuracy on scans with outliers, where distances to
    the data mean little."""
    x, y, z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    keep = (np.abs(x) < 0.95) & (np.abs(y) < 0.95) & ((x - 0.2) ** 2 + (y + 0.1) ** 2 > 0.3**2)
    return float(np.sqrt(((z[keep] - wave_truth(x[keep], y[keep])) ** 2).mean()))


def run_vclay(vclay, path, extra=(), truth=False):
    with tempfile.TemporaryDirectory() as tmp:
        rep = os.path.join(tmp, "r.json")
        surf = os.path.join(tmp, "s.json")
        cmd = [vclay, "fit", path, "--grid", f"{GRID}x{GRID}", "--out", surf, "--report", rep,
               *extra]
        t = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t
        r = json.load(open(rep))
        out = {"rms": r["rms"], "max": r["max"], "time": r["timings"]["total"], "wall": wall,
               "read": r["timings"]["read"], "outliers_detected": r.get("outliers_detected")}
        if truth:
            g = np.linspace(0, 1, 101)
            uv = [[float(a), float(b)] for a in g for b in g]
            params = os.path.join(tmp, "p.json")
            json.dump(uv, open(params, "w"))
            ev = subprocess.run([vclay, "eval", surf, "--params", params], check=True,
                                capture_output=True)
            out["truth_rms"] = truth_rms(np.array(json.loads(ev.stdout)["points"]))
    return out


def run_scipy(pts):
    from scipy.interpolate import LSQBivariateSpline

    x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
    lo, hi = np.array([x.min(), y.min()]), np.array([x.max(), y.max()])
    nin = GRID - DEG - 1
    tx = np.linspace(lo[0], hi[0], nin + 2)[1:-1]
    ty = np.linspace(lo[1], hi[1], nin + 2)[1:-1]
    t = time.perf_counter()
    spl = LSQBivariateSpline(x, y, z, tx, ty, kx=DEG, ky=DEG)
    el = time.perf_counter() - t
    f = lambda u, v: np.column_stack([u, v, spl.ev(u, v)])
    d = closest(f, x.copy(), y.copy(), pts, lo, hi)
    g = np.linspace(-1, 1, 101)
    gx, gy = np.meshgrid(g, g)
    gx, gy = gx.ravel(), gy.ravel()
    grid = np.column_stack([gx, gy, spl.ev(gx, gy)])
    return {**stats(d), "time": el, "vertical_rms": float(np.sqrt(((spl.ev(x, y) - z) ** 2).mean())),
            "truth_rms": truth_rms(grid)}


def run_geomdl(grid):
    from geomdl import fitting
    from scipy.interpolate import BSpline

    nu, nv, _ = grid.shape
    pts = grid.reshape(-1, 3)
    t = time.perf_counter()
    s = fitting.approximate_surface([tuple(p) for p in pts], nu, nv, DEG, DEG,
                                    ctrlpts_size_u=GRID, ctrlpts_size_v=GRID)
    el = time.perf_counter() - t
    cp = np.array(s.ctrlpts).reshape(GRID, GRID, 3)
    ku, kv = np.array(s.knotvector_u), np.array(s.knotvector_v)

    def f(u, v):
        bu = BSpline.design_matrix(np.clip(u, 0, 1), ku, DEG).toarray()
        bv = BSpline.design_matrix(np.clip(v, 0, 1), kv, DEG).toarray()
        return np.stack([((bu @ cp[:, :, c]) * bv).sum(1) for c in range(3)], axis=1)

    # Start from the chord-length parameters of the grid (what geomdl fitted with).
    uu = np.linspace(0, 1, nu)
    vv = np.linspace(0, 1, nv)
    try:
        uk, vl = fitting.compute_params_surface(list(map(tuple, pts)), nu, nv)
        uu, vv = np.array(uk), np.array(vl)
    except Exception:
        pass
    u0 = np.repeat(uu, nv)
    v0 = np.tile(vv, nu)
    d = closest(f, u0, v0, pts, np.zeros(2), np.ones(2))
    return {**stats(d), "time": el}


def main():
    vclay, data = sys.argv[1], sys.argv[2]
    rows = []
    clouds = [("jacksboro.ply", "jacksboro_grid.npy"), ("wave100k.ply", None), ("wave1m.ply", None),
              ("wave100k_outliers.ply", None), ("wave1m_outliers.ply", None)]
    if len(sys.argv) > 3:  # a subset: compare_fit.py VCLAY DATA_DIR wave100k.ply ...
        clouds = [c for c in clouds if c[0] in sys.argv[3:]]
    for name, grid in clouds:
        path = os.path.join(data, name)
        pts = read_ply(path)
        wave = name.startswith("wave")
        row = {"cloud": name, "points": len(pts), "vclay": run_vclay(vclay, path, truth=wave)}
        if "outliers" in name:
            # The default is `--robust auto` (issue 29): plain least squares that goes on
            # robustly once its first round shows gross outliers; `none` is plain throughout.
            row["vclay --robust none"] = run_vclay(vclay, path, ["--robust", "none"], truth=True)
            row["vclay --robust"] = run_vclay(vclay, path, ["--robust"], truth=True)
        if len(pts) <= 200_000:
            row["scipy"] = run_scipy(pts)
            if grid:
                row["geomdl"] = run_geomdl(np.load(os.path.join(data, grid)))
        rows.append(row)
        print(json.dumps(row), flush=True)
    print()
    print("| cloud | points | method | RMS distance | max distance | RMS off the true wave | fit time (s) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        for m in ("vclay", "vclay --robust none", "vclay --robust", "scipy", "geomdl"):
            if m in r:
                x = r[m]
                t = f"{x['truth_rms']:.3g}" if "truth_rms" in x else ""
                print(f"| {r['cloud']} | {r['points']} | {m} | {x['rms']:.4g} | {x['max']:.4g} | {t} | {x['time']:.3f} |")
    from peers_rows import emit

    for r in rows:
        work = f"scan fit, {r['cloud']} ({r['points']:,} points), 32x32 bicubic"
        v = r["vclay"]
        for m, peer in (("scipy", "SciPy FITPACK LSQBivariateSpline"), ("geomdl", "geomdl approximate_surface")):
            if m in r:
                check = f"RMS distance vclay {v['rms']:.3g}, {m} {r[m]['rms']:.3g}"
                if "truth_rms" in v and "truth_rms" in r[m]:
                    check += (f"; RMS off the true wave vclay {v['truth_rms']:.3g}, "
                              f"{m} {r[m]['truth_rms']:.3g}")
                emit("fit", work, "vclay fit, all threads", v["time"] * 1e3, peer, r[m]["time"] * 1e3,
                     check)
    for r in rows:
        if "scipy" in r:
            v, s = r["vclay"], r["scipy"]
            print(f"{r['cloud']}: vclay {s['time'] / v['time']:.1f}x faster than SciPy, "
                  f"RMS ratio vclay/SciPy {v['rms'] / s['rms']:.3f}")


if __name__ == "__main__":
    main()

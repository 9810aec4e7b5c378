#!/usr/bin/env python3
"""Scan data for `vclay fit` benchmarks (issue 20), written as binary PLY (vertex only).

Real scan: the Jacksboro fault digital elevation model that matplotlib ships as sample data
(`mpl-data/sample_data/jacksboro_fault_dem.npz`: 344 x 403 elevations on a 3 arc-second grid
of the US Geological Survey's National Elevation Dataset, Tennessee; USGS data are in the
public domain, the file is distributed with matplotlib under its PSF-style licence). It is
converted to metres (longitude and latitude to a local east/north plane) and written as
jacksboro.ply (138,632 points, height field with about 700 m of relief over 30 x 32 km).

Synthetic scans with a seeded generator: wave100k.ply (100,000 points of
z = 0.15 sin(2x) cos(1.5y) on [-1, 1]^2, normal noise 0.002, a round hole), wave1m.ply
(1,000,000 points, same), wave100k_outliers.ply and wave1m_outliers.ply (the same with 1 % and
2 % one-sided gross outliers, +0.3 to +1.0: issue 29), and, for SciPy and geomdl which want grid data, the same clouds'
grid forms where needed by bench/compare_fit.py.

Usage: get_scan.py OUT_DIR   (needs numpy and matplotlib; bench/check_fit.sh installs them into
a venv under target/)."""

import os
import sys

import numpy as np


def write_ply(path, pts):
    pts = np.ascontiguousarray(pts, dtype="<f8")
    with open(path, "wb") as f:
        f.write(
            (
                "ply\nformat binary_little_endian 1.0\ncomment vclay bench/get_scan.py\n"
                f"element vertex {len(pts)}\nproperty double x\nproperty double y\n"
                "property double z\nend_header\n"
            ).encode()
        )
        f.write(pts.tobytes())


def jacksboro():
    import matplotlib

    path = os.path.join(
        os.path.dirname(matplotlib.__file__), "mpl-data", "sample_data", "jacksboro_fault_dem.npz"
    )
    d = np.load(path)
    z = d["elevation"].astype(float)
    ny, nx = z.shape
    lon = np.linspace(float(d["xmin"]), float(d["xmax"]), nx)
    lat = np.linspace(float(d["ymin"]), float(d["ymax"]), ny)
    lat0 = lat.mean()
    east = (lon - lon[0]) * np.cos(np.radians(lat0)) * 111320.0
    north = (lat - lat[0]) * 110540.0
    e, n = np.meshgrid(east, north)
    return np.column_stack([e.ravel(), n.ravel(), z.ravel()]), (ny, nx)


def wave(n, seed, outliers=0.0):
    """`n` points of the wave with a round hole; a fraction `outliers` of them (seeded) is moved
    up by 0.3 to 1.0, one-sided gross outliers as a scanner's stray returns give (issue 29)."""
    rng = np.random.default_rng(seed)
    pts = []
    got = 0
    while got < n:
        m = 2 * (n - got) + 16
        x = rng.uniform(-1, 1, m)
        y = rng.uniform(-1, 1, m)
        keep = (x - 0.2) ** 2 + (y + 0.1) ** 2 >= 0.25**2
        x, y = x[keep][: n - got], y[keep][: n - got]
        z = 0.15 * np.sin(2 * x) * np.cos(1.5 * y) + rng.normal(0, 0.002, len(x))
        pts.append(np.column_stack([x, y, z]))
        got += len(x)
    pts = np.vstack(pts)
    if outliers > 0:
        k = rng.random(len(pts)) < outliers
        pts[k, 2] += rng.uniform(0.3, 1.0, int(k.sum()))
    return pts


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "target/fit-data"
    os.makedirs(out, exist_ok=True)
    pts, shape = jacksboro()
    write_ply(os.path.join(out, "jacksboro.ply"), pts)
    np.save(os.path.join(out, "jacksboro_grid.npy"), pts.reshape(shape[0], shape[1], 3))
    write_ply(os.path.join(out, "wave100k.ply"), wave(100_000, 1))
    write_ply(os.path.join(out, "wave1m.ply"), wave(1_000_000, 2))
    write_ply(os.path.join(out, "wave100k_outliers.ply"), wave(100_000, 3, outliers=0.01))
    write_ply(os.path.join(out, "wave1m_outliers.ply"), wave(1_000_000, 4, outliers=0.02))
    print(f"get_scan: wrote jacksboro.ply ({len(pts)} points), wave100k.ply, wave1m.ply, "
          f"wave100k_outliers.ply (1 % outliers), wave1m_outliers.ply (2 %) to {out}")


if __name__ == "__main__":
    main()

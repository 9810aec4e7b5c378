#!/usr/bin/env python3
"""A 1M-vertex free-form deformation: vclay beside PyGeM's FFD, in one run (issue 31).

The same deformation in both: the UV sphere of 1000 x 1000 vertices of
crates/vclay-ffd/examples/bench_deform.rs, a cubic lattice of 4 x 4 x 4 control points (one
Bezier volume: Bernstein polynomials of degree 3, Sederberg and Parry's FFD, which is what
PyGeM's `FFD(n_control_points=[4, 4, 4])` evaluates) over the sphere's bounding box grown by 5 %
on each side, and the same displacement of every one of the 64 control points (definition in
crates/vclay-ffd/examples/ffd_peer.rs).

1. `cargo run --release -p vclay-ffd --example ffd_peer` deforms the sphere with vclay, times
   the embedding (parameters and basis values of every vertex) and the deformation on 1 thread
   and on rayon's pool, and writes the rest and deformed positions and the box and
   displacements (meta.json) under target/ffd-peers/.
2. This script sets PyGeM up with the same box in PyGeM's conventions (`box_origin` = the
   lattice's low corner, `box_length` = its extent, no rotation; the weights `array_mu_*` are
   the displacements divided by the box length along their axis), deforms the same rest
   points, and CHECKS that both agree: the largest distance between PyGeM's and vclay's
   deformed points must stay under TOLERANCE times the box diagonal (both evaluate the same
   polynomial in f64; PyGeM's affine maps go through a least-squares fit, so equality to the
   last bit is not expected). Only then does it time PyGeM's call (best of runs), which does
   all the work each time: map to the unit cube, Bernstein values, deformation, map back.

Compared: a one-shot FFD of the point set (vclay: embed + deform; PyGeM: one call), and the
repeated deformation of an interactive edit (vclay keeps the embedding and only deforms; PyGeM
has no such split, so its figure is again the whole call).

PyGeM (mathLab's "Python Geometrical Morphing") is not on PyPI: the PyPI project named `pygem`
is an unrelated glacier model. The script therefore installs PyGeM from a source checkout named
by VCLAY_PYGEM_SRC (anything `pip install` accepts: a checkout of the repository mathLab/PyGeM,
a wheel), without its optional dependencies, into bench/.venv-ffd with the pinned PyPI packages
below (numpy and scipy for its FFD, matplotlib because `import pygem` imports it). It prints
SKIPPED and exits 0 when PyGeM cannot be had (no VCLAY_PYGEM_SRC, VCLAY_NO_INSTALL set, or pip
failed). The measured run recorded in docs/performance.md used PyGeM 2.0.0 at commit
b482f27743d900cec651be1145b72400ecca72b1 (2025-12-05).

Usage: python3 bench/ffd_peers.py      Env: VCLAY_FFD_SIDE (vertices per side, default 1000),
VCLAY_FFD_RUNS (timed runs of each, default 5 for vclay, at most 3 for PyGeM).
Writes bench/ffd_peers.md and prints it; exits 1 when the two disagree.
"""

import json
import os
import platform
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
VENV = os.path.join(HERE, ".venv-ffd")
PINS = ["numpy==2.4.6", "scipy==1.17.1", "matplotlib==3.10.8"]
# Largest allowed distance between PyGeM's and vclay's deformed points, relative to the
# lattice's diagonal.
TOLERANCE = 1e-12
PROBE = "import numpy, scipy, matplotlib, pygem; pygem.FFD"


def skip(why):
    print(f"ffd_peers: SKIPPED: {why}")
    sys.exit(0)


def ensure_venv():
    py = os.path.join(VENV, "bin", "python")
    if sys.executable == py:
        return
    ok = os.path.exists(py) and subprocess.run(
        [py, "-c", PROBE], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode == 0
    if not ok:
        if os.environ.get("VCLAY_NO_INSTALL"):
            skip(f"PyGeM/numpy/scipy not installed in {VENV} (VCLAY_NO_INSTALL set)")
        src = os.environ.get("VCLAY_PYGEM_SRC")
        if not src:
            skip("PyGeM is not on PyPI (the PyPI project 'pygem' is a glacier model); "
                 "set VCLAY_PYGEM_SRC to a source checkout of mathLab/PyGeM")
        print(f"ffd_peers: installing {' '.join(PINS)} and PyGeM from {src} into {VENV}",
              flush=True)
        try:
            if not os.path.exists(py):
                subprocess.check_call([sys.executable, "-m", "venv", VENV])
            subprocess.check_call([py, "-m", "pip", "install", "-q", *PINS])
            subprocess.check_call([py, "-m", "pip", "install", "-q", "--no-deps", src])
            subprocess.check_call([py, "-c", PROBE])
        except (subprocess.CalledProcessError, OSError) as e:
            skip(f"could not install PyGeM and its packages ({e})")
    os.execv(py, [py] + sys.argv)


def best_ms(fn, runs):
    best = float("inf")
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best * 1e3


def main():
    ensure_venv()
    import numpy as np
    import pygem
    from pygem import FFD
    from peers_rows import cpu_name, emit

    side = int(os.environ.get("VCLAY_FFD_SIDE", "1000"))
    runs = int(os.environ.get("VCLAY_FFD_RUNS", "5"))
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    subprocess.check_call(["cargo", "build", "--release", "-q", "-p", "vclay-ffd", "--example",
                           "ffd_peer"], cwd=ROOT)
    work = os.path.join(target, "ffd-peers")
    out = subprocess.check_output([os.path.join(target, "release", "examples", "ffd_peer"), work,
                                   str(side), str(runs)], cwd=ROOT, text=True)
    meta = json.loads(out.strip().splitlines()[-1])
    rest = np.fromfile(os.path.join(work, "rest.f64"), dtype="<f8").reshape(-1, 3)
    vclay = np.fromfile(os.path.join(work, "deformed.f64"), dtype="<f8").reshape(-1, 3)
    n = meta["vertices"]
    if rest.shape != (n, 3) or vclay.shape != (n, 3):
        sys.exit(f"ffd_peers: expected {n} x 3 points, read {rest.shape} and {vclay.shape}")

    lo, hi = np.array(meta["box_lo"]), np.array(meta["box_hi"])
    length = hi - lo
    ffd = FFD(meta["control_points"])
    ffd.box_origin = lo.copy()
    ffd.box_length = length.copy()
    ffd.rot_angle = np.zeros(3)
    for i, j, k, dx, dy, dz in meta["displacements"]:
        ijk = (int(i), int(j), int(k))
        ffd.array_mu_x[ijk] = dx / length[0]
        ffd.array_mu_y[ijk] = dy / length[1]
        ffd.array_mu_z[ijk] = dz / length[2]

    peer = ffd(rest)
    diag = float(np.linalg.norm(length))
    dev = float(np.linalg.norm(peer - vclay, axis=1).max())
    moved = float(np.linalg.norm(vclay - rest, axis=1).max())
    agree = dev <= TOLERANCE * diag
    check = (f"largest point distance {dev / diag:.1e} of the box diagonal (tolerance "
             f"{TOLERANCE:.0e}); largest displacement {moved / diag:.3f} of it")

    peer_runs = max(1, min(3, runs))
    t_peer = best_ms(lambda: ffd(rest), peer_runs) if agree else float("nan")
    one_1 = meta["embed_ms_1_thread"] + meta["deform_ms_1_thread"]
    one_all = meta["embed_ms_all_threads"] + meta["deform_ms_all_threads"]
    threads = meta["threads"]
    yard = meta["yardstick"]
    pg = f"PyGeM {pygem.__version__} FFD (NumPy {np.__version__})"
    shot = f"FFD of {n:,} vertices, 4^3 cubic lattice, one shot (parameters + deformation)"
    again = f"FFD of {n:,} vertices, 4^3 cubic lattice, again after an edit (embedding kept)"
    rows = [
        (shot, "1 thread", one_1),
        (shot, f"{threads} threads", one_all),
        (again, "1 thread", meta["deform_ms_1_thread"]),
        (again, f"{threads} threads", meta["deform_ms_all_threads"]),
    ]
    text = "\n".join([
        f"Machine: {cpu_name()}, {os.cpu_count()} logical CPUs; Python {platform.python_version()}, "
        f"{pg}, SciPy {__import__('scipy').__version__}. 1-minute load average {meta['load1']} "
        f"before vclay's timing, {os.getloadavg()[0]:.2f} after PyGeM's; yardstick "
        f"v{yard['version']} {yard['start_ms']:.3f} / {yard['end_ms']:.3f} ms (start / end of "
        "vclay's example).",
        f"Mesh: UV sphere, {n:,} vertices, all inside the lattice ({meta['embedded']:,} embedded "
        f"by vclay). Best of {runs} runs (vclay) and {peer_runs} (PyGeM), wall ms.",
        f"Agreement: {check}: {'PASS' if agree else 'FAIL'}.",
        "",
        "| workload | vclay | vclay ms | PyGeM ms (whole call) | PyGeM / vclay |",
        "| --- | --- | ---: | ---: | ---: |",
        *[f"| {w} | {c} | {ms:.1f} | {t_peer:.1f} | {t_peer / ms:.1f}x |" for w, c, ms in rows],
        "",
        f"vclay parts: embed {meta['embed_ms_1_thread']:.1f} ms (1 thread) / "
        f"{meta['embed_ms_all_threads']:.1f} ms ({threads}); deform "
        f"{meta['deform_ms_1_thread']:.1f} / {meta['deform_ms_all_threads']:.1f} ms; deform CPU "
        f"time on 1 thread {meta['deform_cpu_ms_1_thread'] or float('nan'):.1f} ms. PyGeM's "
        "call is NumPy array code on one thread, save the BLAS product of its affine maps.",
    ]) + "\n"
    with open(os.path.join(HERE, "ffd_peers.md"), "w") as f:
        f.write(text)
    print(text)
    if not agree:
        sys.exit(f"ffd_peers: PyGeM and vclay disagree: {check}")
    for w, c, ms in rows:
        emit("ffd", w, f"vclay, {c}", ms, pg, t_peer, check)


if __name__ == "__main__":
    main()

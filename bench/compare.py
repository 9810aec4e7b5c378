#!/usr/bin/env python3
"""vclay against its peers, in one run on one machine.

Peers: geomdl (NURBS-Python, pure Python) and OpenNURBS through rhino3dm (C++ behind pybind11).
The same 16x16 rational bicubic surface (defined identically in crates/vclay-cli/src/bench.rs) is
built in each library; points are first checked to agree with `vclay eval` (a cross-check of
vclay's evaluation against two independent implementations), then timed.

OpenNURBS has no batch API in rhino3dm, so every point costs one Python -> C++ call. The script
measures that call overhead with a trivial rhino3dm call and reports the per-point time both raw
and with the overhead subtracted (an estimate of OpenNURBS's own cost).

Usage: python3 bench/compare.py            (creates bench/.venv with geomdl and rhino3dm)
Writes bench/results.md and prints it.
"""
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
VENV = os.path.join(HERE, ".venv")


def ensure_venv():
    py = os.path.join(VENV, "bin", "python")
    if sys.executable != py:
        if not os.path.exists(py):
            subprocess.check_call([sys.executable, "-m", "venv", VENV])
            subprocess.check_call([py, "-m", "pip", "install", "-q", "geomdl", "rhino3dm"])
        os.execv(py, [py] + sys.argv)


N = 16


def surface_data():
    import math
    pts, ws = [], []
    for i in range(N):
        for j in range(N):
            x, y = i / (N - 1), j / (N - 1)
            pts.append((x, y, 0.2 * math.sin(7.0 * x) * math.cos(5.0 * y)))
            ws.append(1.0 + 0.25 * ((i * N + j) % 5))
    spans = N - 3
    knots = [0.0] * 4 + [k / spans for k in range(1, spans)] + [1.0] * 4
    return pts, ws, knots


def params(count):
    return [(((k * 37) % count) / (count - 1), ((k * 101) % count) / (count - 1)) for k in range(count)]


def best_time(fn, budget=1.0):
    best, start, runs = float("inf"), time.perf_counter(), 0
    while runs < 3 or time.perf_counter() - start < budget:
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
        runs += 1
    return best


def main():
    ensure_venv()
    import geomdl
    from geomdl import NURBS
    import rhino3dm

    subprocess.check_call(["cargo", "build", "--release", "-q", "-p", "vclay-cli"], cwd=ROOT)
    vclay = os.path.join(ROOT, "target", "release", "vclay")
    pts, ws, knots = surface_data()

    # vclay model file for the agreement check.
    model = {
        "type": "nurbs-surface", "degree": [3, 3], "knots": [knots, knots],
        "control_points": [[list(pts[i * N + j]) for j in range(N)] for i in range(N)],
        "weights": [[ws[i * N + j] for j in range(N)] for i in range(N)],
    }
    check = params(997)
    with tempfile.TemporaryDirectory() as tmp:
        mp, pp = os.path.join(tmp, "m.json"), os.path.join(tmp, "p.json")
        json.dump(model, open(mp, "w"))
        json.dump([list(t) for t in check], open(pp, "w"))
        ref = json.loads(subprocess.check_output([vclay, "eval", mp, "--params", pp]))["points"]

    # geomdl
    g = NURBS.Surface()
    g.degree_u, g.degree_v = 3, 3
    g.ctrlpts_size_u, g.ctrlpts_size_v = N, N
    g.ctrlptsw = [[p[0] * w, p[1] * w, p[2] * w, w] for p, w in zip(pts, ws)]
    g.knotvector_u, g.knotvector_v = knots, knots
    # rhino3dm / OpenNURBS: homogeneous control points, knots without the superfluous end knots.
    r = rhino3dm.NurbsSurface.Create(3, True, 4, 4, N, N)
    for i in range(N):
        for j in range(N):
            p, w = pts[i * N + j], ws[i * N + j]
            r.Points[i, j] = rhino3dm.Point4d(p[0] * w, p[1] * w, p[2] * w, w)
    for k, v in enumerate(knots[1:-1]):
        r.KnotsU[k] = v
        r.KnotsV[k] = v

    def dev(points):
        return max(max(abs(a - b) for a, b in zip(p, q)) for p, q in zip(points, ref))

    dev_geomdl = dev(g.evaluate_list(check))
    dev_rhino = dev([(q.X, q.Y, q.Z) for q in (r.PointAt(u, v) for u, v in check)])

    vc = json.loads(subprocess.check_output([vclay, "bench", "--seconds", "1"]))
    timed = params(10000)
    t_rh = best_time(lambda: [r.PointAt(u, v) for u, v in timed]) / len(timed)
    t_call = best_time(lambda: [r.Degree(0) for _ in timed]) / len(timed)
    small = params(2000)
    t_gd = best_time(lambda: g.evaluate_list(small), budget=2.0) / len(small)

    cpu = platform.processor() or platform.machine()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    ns = 1e9
    rows = [
        ("vclay grid, 1 thread", 1e9 / vc["surface_grid_points_per_second_1_thread"], vc["surface_grid_points_per_second_1_thread"] / 1e6),
        (f"vclay grid, all threads ({vc['threads']})", 1e9 / vc["surface_grid_points_per_second_all_threads"], vc["surface_grid_points_per_second_all_threads"] / 1e6),
        ("vclay point by point, 1 thread", vc["surface_point_ns"], 1e3 / vc["surface_point_ns"]),
        ("OpenNURBS (rhino3dm) PointAt, raw", t_rh * ns, 1e-6 / t_rh),
        ("OpenNURBS PointAt minus Python call overhead", (t_rh - t_call) * ns, 1e-6 / max(t_rh - t_call, 1e-12)),
        (f"geomdl {geomdl.__version__} evaluate_list", t_gd * ns, 1e-6 / t_gd),
    ]
    out = [
        f"Machine: {cpu}, {os.cpu_count()} logical CPUs; Python {platform.python_version()}, "
        f"rhino3dm {rhino3dm.__version__}, geomdl {geomdl.__version__}.",
        "Surface: 16x16 rational bicubic; vclay grid 1000x1000, point-by-point 10,000 scattered parameters.",
        "",
        "| evaluator | ns per point | million points/s |",
        "| --- | ---: | ---: |",
    ] + [f"| {n} | {t:.1f} | {m:.2f} |" for n, t, m in rows] + [
        "",
        f"vclay cubic curve, point by point: {vc['curve_point_ns']:.1f} ns per point.",
        f"Python -> rhino3dm call overhead (trivial call): {t_call * ns:.1f} ns.",
        f"Agreement with `vclay eval` over 997 parameters: geomdl {dev_geomdl:.1e}, OpenNURBS {dev_rhino:.1e} (largest coordinate difference).",
    ]
    text = "\n".join(out) + "\n"
    open(os.path.join(HERE, "results.md"), "w").write(text)
    print(text)
    if dev_geomdl > 1e-9 or dev_rhino > 1e-9:
        sys.exit("peers disagree with vclay eval by more than 1e-9")
    # One row per peer for bench/peers.sh (bench/peers_rows.py): ms per million scattered points.
    from peers_rows import emit

    work = "surface evaluation, 16x16 rational bicubic, scattered points (ms per million)"
    vclay_ms = vc["surface_point_ns"]
    for peer, ms, d in [(f"OpenNURBS (rhino3dm {rhino3dm.__version__}) PointAt", t_rh * ns, dev_rhino),
                        ("OpenNURBS PointAt less the Python call", (t_rh - t_call) * ns, dev_rhino),
                        (f"geomdl {geomdl.__version__} evaluate_list", t_gd * ns, dev_geomdl)]:
        emit("eval", work, "vclay point by point, 1 thread", vclay_ms, peer, ms,
             f"largest coordinate difference to `vclay eval` {d:.1e} (tolerance 1e-9)")


if __name__ == "__main__":
    main()

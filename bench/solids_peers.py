"""One mass-spring step of vclay's dynamic solid lattice beside Taichi and NVIDIA Warp on the CPU.

Usage: python bench/solids_peers.py [--seconds S] [--out FILE.md] LEVEL_DIR...

Each LEVEL_DIR holds the .npy files and meta.json written by
`cargo run --release -p vclay-solids --example spring_export -- LEVEL LEVEL_DIR`
(layout in that example's docs). For each lattice, this script runs, each in its own process
(Taichi's thread count is fixed per process):
  - Taichi (ti.cpu, f64) with cpu_max_num_threads = 1 and = 2,
  - Warp (device="cpu", float64; Warp runs CPU kernels on one thread),
implementing the SAME step as vclay's example: zero the forces, edge springs, virtual springs
(corner m, neighbours a, b: x = d_m - (d_a + d_b)/2, g = k (|x| - l0) x/|x|, f_m -= g,
f_a += g/2, f_b += g/2; edges x = d_b - d_a, f_a += g, f_b -= g), scattered with atomic adds
(the idiomatic way in both), then v += dt f/m, x += dt v. Two variants of the virtual springs:
"corner" (one thread per (m, a, b) triple, 3 atomic scatters) and, when every face is a quad,
"quad" (one thread per face, its 4 virtual springs, 4 atomic scatters: the same loop as vclay's
add_forces). Forces at the exported state are compared
with vclay's (max |f_peer - f_vclay| / max |f_vclay|), the kernels are warmed up (JIT), and the
median step time is reported. Prints a Markdown table and writes it to --out.
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np

DT = 1e-4


def load(d):
    """The exported lattice as numpy arrays."""
    a = {k: np.load(os.path.join(d, k + ".npy")) for k in
         ["points", "masses", "edges", "edge_rest", "edge_k", "corners", "corner_rest",
          "corner_k", "forces"]}
    with open(os.path.join(d, "meta.json")) as f:
        a["meta"] = json.load(f)
    n = a["points"].shape[0]
    for k in ["edges", "corners"]:
        if a[k].size and int(a[k].max()) >= n:
            raise SystemExit(f"{d}/{k}.npy: index {int(a[k].max())} out of range (n = {n})")
        a[k] = a[k].astype(np.int32)
    a["quads"] = quads(a["corners"])
    return a


def quads(c):
    """The faces as quads (nf, 4) when every face is a quad (corners come face by face, in loop
    order, from spring_export), else None."""
    if len(c) % 4:
        return None
    v = c[:, 0].reshape(-1, 4)
    if (c[:, 1].reshape(-1, 4) == np.roll(v, 1, axis=1)).all() and \
            (c[:, 2].reshape(-1, 4) == np.roll(v, -1, axis=1)).all():
        return np.ascontiguousarray(v)
    return None


def rel_err(f, ref):
    return float(np.abs(f - ref).max() / max(np.abs(ref).max(), 1e-300))


def time_loop(step, sync, seconds):
    """Median milliseconds of `step` over repetitions for about `seconds` (5..500 reps)."""
    times = []
    t0 = time.perf_counter()
    while len(times) < 5 or (time.perf_counter() - t0 < seconds and len(times) < 500):
        t = time.perf_counter()
        step()
        sync()
        times.append((time.perf_counter() - t) * 1e3)
    return statistics.median(times), len(times)


def run_taichi(a, threads, seconds, variant):
    import taichi as ti

    ti.init(arch=ti.cpu, default_fp=ti.f64, default_ip=ti.i32, cpu_max_num_threads=threads,
            offline_cache=False, log_level=ti.WARN)
    n, ne, nc = len(a["points"]), len(a["edges"]), len(a["corners"])
    x = ti.Vector.field(3, ti.f64, n)
    v = ti.Vector.field(3, ti.f64, n)
    f = ti.Vector.field(3, ti.f64, n)
    inv_m = ti.field(ti.f64, n)
    edges = ti.Vector.field(2, ti.i32, ne)
    erest = ti.field(ti.f64, ne)
    ek = ti.field(ti.f64, ne)
    corners = ti.Vector.field(3, ti.i32, nc)
    crest = ti.field(ti.f64, nc)
    ck = ti.field(ti.f64, nc)
    x.from_numpy(a["points"])
    v.fill(0.0)
    inv_m.from_numpy(1.0 / a["masses"])
    edges.from_numpy(a["edges"])
    erest.from_numpy(a["edge_rest"])
    ek.from_numpy(a["edge_k"])
    corners.from_numpy(a["corners"])
    crest.from_numpy(a["corner_rest"])
    ck.from_numpy(a["corner_k"])
    nq = len(a["quads"]) if variant == "quad" else 0
    quad = ti.Vector.field(4, ti.i32, max(nq, 1))
    qrest = ti.Vector.field(4, ti.f64, max(nq, 1))
    qk = ti.Vector.field(4, ti.f64, max(nq, 1))
    if nq:
        quad.from_numpy(a["quads"])
        qrest.from_numpy(np.ascontiguousarray(a["corner_rest"].reshape(-1, 4)))
        qk.from_numpy(np.ascontiguousarray(a["corner_k"].reshape(-1, 4)))

    @ti.func
    def edge_spring(e):
        i, j = edges[e][0], edges[e][1]
        d = x[j] - x[i]
        l = d.norm()
        if l > 0.0:
            g = d * (ek[e] * (l - erest[e]) / l)
            f[i] += g  # atomic add inside a parallel loop
            f[j] -= g

    @ti.func
    def virtual_spring(c):
        m, p, q = corners[c][0], corners[c][1], corners[c][2]
        d = x[m] - 0.5 * (x[p] + x[q])
        l = d.norm()
        if l > 0.0:
            g = d * (ck[c] * (l - crest[c]) / l)
            f[m] -= g
            f[p] += 0.5 * g
            f[q] += 0.5 * g

    @ti.func
    def pull(d, k, l0):
        """k (|d| - l0) d / |d| (zero when |d| = 0)."""
        l = d.norm()
        g = ti.Vector([0.0, 0.0, 0.0])
        if l > 0.0:
            g = d * (k * (l - l0) / l)
        return g

    @ti.func
    def quad_springs(q):
        # The four virtual springs of one quad face, as vclay's own loop: corners 0 and 2 share
        # the virtual point (p1 + p3) / 2, corners 1 and 3 share (p0 + p2) / 2; four scatters.
        i = quad[q]
        p0, p1, p2, p3 = x[i[0]], x[i[1]], x[i[2]], x[i[3]]
        m13, m02 = 0.5 * (p1 + p3), 0.5 * (p0 + p2)
        g0 = pull(p0 - m13, qk[q][0], qrest[q][0])
        g1 = pull(p1 - m02, qk[q][1], qrest[q][1])
        g2 = pull(p2 - m13, qk[q][2], qrest[q][2])
        g3 = pull(p3 - m02, qk[q][3], qrest[q][3])
        f[i[0]] += 0.5 * (g1 + g3) - g0
        f[i[1]] += 0.5 * (g0 + g2) - g1
        f[i[2]] += 0.5 * (g1 + g3) - g2
        f[i[3]] += 0.5 * (g0 + g2) - g3

    @ti.func
    def all_springs():
        for i in f:
            f[i] = ti.Vector([0.0, 0.0, 0.0])
        for e in range(ne):
            edge_spring(e)
        if ti.static(nq > 0):
            for q in range(nq):
                quad_springs(q)
        else:
            for c in range(nc):
                virtual_spring(c)

    @ti.kernel
    def forces():
        all_springs()

    @ti.kernel
    def step(dt: ti.f64):
        all_springs()
        for i in x:
            v[i] += dt * inv_m[i] * f[i]
            x[i] += dt * v[i]

    t = time.perf_counter()
    forces()
    ti.sync()
    err = rel_err(f.to_numpy(), a["forces"])
    for _ in range(3):
        step(DT)
    ti.sync()
    compile_s = time.perf_counter() - t
    ms, reps = time_loop(lambda: step(DT), ti.sync, seconds)
    if not np.isfinite(x.to_numpy()).all():
        raise SystemExit("taichi: the timed steps diverged")
    return {"ms": ms, "reps": reps, "rel_err": err, "compile_s": compile_s,
            "version": ".".join(map(str, ti.__version__))}


def run_warp(a, seconds, variant):
    import warp as wp

    wp.config.quiet = True
    wp.init()
    dev = "cpu"
    vec = wp.vec3d
    f64 = wp.float64

    @wp.kernel
    def zero(f: wp.array(dtype=vec)):
        i = wp.tid()
        f[i] = vec(f64(0.0), f64(0.0), f64(0.0))

    @wp.kernel
    def edge_springs(x: wp.array(dtype=vec), edges: wp.array2d(dtype=wp.int32),
                     rest: wp.array(dtype=f64), k: wp.array(dtype=f64), f: wp.array(dtype=vec)):
        e = wp.tid()
        i = edges[e, 0]
        j = edges[e, 1]
        d = x[j] - x[i]
        l = wp.length(d)
        if l > f64(0.0):
            g = d * (k[e] * (l - rest[e]) / l)
            wp.atomic_add(f, i, g)
            wp.atomic_sub(f, j, g)

    @wp.kernel
    def virtual_springs(x: wp.array(dtype=vec), corners: wp.array2d(dtype=wp.int32),
                        rest: wp.array(dtype=f64), k: wp.array(dtype=f64),
                        f: wp.array(dtype=vec)):
        c = wp.tid()
        m = corners[c, 0]
        p = corners[c, 1]
        q = corners[c, 2]
        d = x[m] - f64(0.5) * (x[p] + x[q])
        l = wp.length(d)
        if l > f64(0.0):
            g = d * (k[c] * (l - rest[c]) / l)
            h = f64(0.5) * g
            wp.atomic_sub(f, m, g)
            wp.atomic_add(f, p, h)
            wp.atomic_add(f, q, h)

    @wp.func
    def pull(d: vec, k: f64, l0: f64):
        l = wp.length(d)
        g = vec(f64(0.0), f64(0.0), f64(0.0))
        if l > f64(0.0):
            g = d * (k * (l - l0) / l)
        return g

    @wp.kernel
    def quad_springs(x: wp.array(dtype=vec), quads: wp.array2d(dtype=wp.int32),
                     rest: wp.array2d(dtype=f64), k: wp.array2d(dtype=f64),
                     f: wp.array(dtype=vec)):
        # As vclay's own loop: four virtual springs per quad face, four scatters.
        q = wp.tid()
        i0 = quads[q, 0]
        i1 = quads[q, 1]
        i2 = quads[q, 2]
        i3 = quads[q, 3]
        p0 = x[i0]
        p1 = x[i1]
        p2 = x[i2]
        p3 = x[i3]
        half = f64(0.5)
        m13 = half * (p1 + p3)
        m02 = half * (p0 + p2)
        g0 = pull(p0 - m13, k[q, 0], rest[q, 0])
        g1 = pull(p1 - m02, k[q, 1], rest[q, 1])
        g2 = pull(p2 - m13, k[q, 2], rest[q, 2])
        g3 = pull(p3 - m02, k[q, 3], rest[q, 3])
        wp.atomic_add(f, i0, half * (g1 + g3) - g0)
        wp.atomic_add(f, i1, half * (g0 + g2) - g1)
        wp.atomic_add(f, i2, half * (g1 + g3) - g2)
        wp.atomic_add(f, i3, half * (g0 + g2) - g3)

    @wp.kernel
    def update(x: wp.array(dtype=vec), v: wp.array(dtype=vec), f: wp.array(dtype=vec),
               inv_m: wp.array(dtype=f64), dt: f64):
        i = wp.tid()
        v[i] = v[i] + (dt * inv_m[i]) * f[i]
        x[i] = x[i] + dt * v[i]

    n, ne, nc = len(a["points"]), len(a["edges"]), len(a["corners"])
    x = wp.array(a["points"], dtype=vec, device=dev)
    v = wp.zeros(n, dtype=vec, device=dev)
    f = wp.zeros(n, dtype=vec, device=dev)
    inv_m = wp.array(1.0 / a["masses"], dtype=f64, device=dev)
    edges = wp.array(a["edges"], dtype=wp.int32, device=dev)
    erest = wp.array(a["edge_rest"], dtype=f64, device=dev)
    ek = wp.array(a["edge_k"], dtype=f64, device=dev)
    corners = wp.array(a["corners"], dtype=wp.int32, device=dev)
    crest = wp.array(a["corner_rest"], dtype=f64, device=dev)
    ck = wp.array(a["corner_k"], dtype=f64, device=dev)
    if variant == "quad":
        nq = len(a["quads"])
        quads = wp.array(a["quads"], dtype=wp.int32, device=dev)
        qrest = wp.array(a["corner_rest"].reshape(-1, 4), dtype=f64, device=dev)
        qk = wp.array(a["corner_k"].reshape(-1, 4), dtype=f64, device=dev)

    def forces():
        wp.launch(zero, dim=n, inputs=[f], device=dev)
        wp.launch(edge_springs, dim=ne, inputs=[x, edges, erest, ek, f], device=dev)
        if variant == "quad":
            wp.launch(quad_springs, dim=nq, inputs=[x, quads, qrest, qk, f], device=dev)
        else:
            wp.launch(virtual_springs, dim=nc, inputs=[x, corners, crest, ck, f], device=dev)

    def step():
        forces()
        wp.launch(update, dim=n, inputs=[x, v, f, inv_m, f64(DT)], device=dev)

    t = time.perf_counter()
    forces()
    wp.synchronize()
    err = rel_err(f.numpy(), a["forces"])
    for _ in range(3):
        step()
    wp.synchronize()
    compile_s = time.perf_counter() - t
    ms, reps = time_loop(step, wp.synchronize, seconds)
    if not np.isfinite(x.numpy()).all():
        raise SystemExit("warp: the timed steps diverged")
    return {"ms": ms, "reps": reps, "rel_err": err, "compile_s": compile_s,
            "version": wp.config.version}


def worker(args):
    a = load(args.worker_dir)
    if args.worker == "taichi":
        r = run_taichi(a, args.threads, args.seconds, args.variant)
    else:
        r = run_warp(a, args.seconds, args.variant)
    print("RESULT " + json.dumps(r), flush=True)


def spawn(kind, d, seconds, variant, threads=1):
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", kind, "--worker-dir", d,
           "--threads", str(threads), "--seconds", str(seconds), "--variant", variant]
    p = subprocess.run(cmd, capture_output=True, text=True)
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    sys.stderr.write(f"{kind} ({variant}, threads {threads}) failed on {d}:\n{p.stdout[-2000:]}"
                     f"{p.stderr[-4000:]}\n")
    return None


def emit_rows(meta, best, versions):
    """The rows of bench/peers.sh's table (bench/peers_rows.py): vclay beside each peer at an
    equal thread count, the peer's faster kernel variant, only peers whose forces agreed."""
    from peers_rows import emit

    work = (f"mass-spring step, level {meta['level']} ({meta['points']:,} points, "
            f"{meta['springs']:,} springs)")
    for key, name, vclay, ms in [("ti1", "Taichi {} (CPU), 1 thread", "vclay, 1 thread", "seq_ms"),
                                 ("ti2", "Taichi {} (CPU), 2 threads", "vclay, 2 threads", "par_ms"),
                                 ("wp", "Warp {} (CPU, 1 thread)", "vclay, 1 thread", "seq_ms")]:
        if key in best:
            kind = "warp" if key == "wp" else "taichi"
            emit("solids", work, vclay, meta[ms], name.format(versions.get(kind, "?")),
                 best[key][0], f"forces agree to {best[key][1]:.1e} relative (tolerance 1e-10)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="*")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--out", default=None)
    ap.add_argument("--worker", choices=["taichi", "warp"])
    ap.add_argument("--worker-dir")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--variant", choices=["corner", "quad"], default="corner")
    args = ap.parse_args()
    if args.worker:
        return worker(args)
    if not args.dirs:
        ap.error("give at least one LEVEL_DIR")
    from peers_rows import cpu_name

    cpu = cpu_name()
    rows, versions, errs = [], {}, []
    for d in args.dirs:
        a = load(d)
        meta = a["meta"]
        load0 = os.getloadavg()[0]
        variants = ["corner"] + (["quad"] if a["quads"] is not None else [])
        cells, best = {}, {}
        for key, kind, threads in [("ti1", "taichi", 1), ("ti2", "taichi", 2), ("wp", "warp", 1)]:
            res = [spawn(kind, d, args.seconds, v, threads) for v in variants]
            cells[key] = " / ".join(f"{r['ms']:.3f}" if r else "failed" for r in res)
            for v, r in zip(variants, res):
                if not r:
                    errs.append(f"{d}: {kind} ({v}, {threads} threads) failed")
                    continue
                versions[kind] = r["version"]
                cells["err"] = max(cells.get("err", 0.0), r["rel_err"])
                if not r["rel_err"] < 1e-10:
                    errs.append(f"{d}: {kind} ({v}, {threads} threads) forces differ from "
                                f"vclay's by {r['rel_err']:.1e} (relative)")
                elif key not in best or r["ms"] < best[key][0]:
                    best[key] = (r["ms"], r["rel_err"])
        emit_rows(meta, best, versions)
        rows.append(
            f"| {meta['level']} | {meta['points']:,} | {meta['springs']:,} | "
            f"{meta['seq_ms']:.3f} | {meta['par_ms']:.3f} | {cells['ti1']} | {cells['ti2']} | "
            f"{cells['wp']} | {cells.get('err', float('nan')):.1e} | "
            f"{meta.get('load1', float('nan')):.2f} / {load0:.2f} |")
        print(rows[-1], file=sys.stderr, flush=True)
    lines = [
        f"Machine: {cpu}, {os.cpu_count()} CPUs. Versions: Python {platform.python_version()}, "
        f"NumPy {np.__version__}, Taichi {versions.get('taichi', '-')}, "
        f"Warp {versions.get('warp', '-')}. Median ms of one step (zero forces, all springs, "
        f"v += dt f/m, x += dt v), f64. Peer cells: virtual springs per corner (3 atomic "
        f"scatters each) / per quad face (4 scatters per face, as vclay's loop). Load: the "
        f"machine's 1-minute load average before vclay's timing / before the peers' runs.",
        "",
        "| level | data points | springs | vclay 1 thread | vclay 2 threads | "
        "Taichi 1 thread | Taichi 2 threads | Warp (CPU, 1 thread) | "
        "max force rel. error (peers vs vclay) | load (vclay / peers) |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *rows,
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        tmp = args.out + ".tmp"
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, args.out)
    if errs:
        print("\n".join(errs), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()

"""Benchmark of the Python module against the Rust kernel (issue 21), one run, JSON out.

- batched evaluation of 1M scattered points of the benchmark surface (16 x 16 rational
  bicubic, the definition of `vclay bench` / `bench/compare.py`) from Python, on one thread
  and on all, beside `vclay bench`'s Rust figures from the same minutes;
- grid evaluation 1000 x 1000 from Python beside Rust's, into a new array and into an
  existing one (`out=`, as Rust's benchmark reuses its buffer);
- per-call cost of `Surface.point(u, v)` (one point, Python tuple out) minus the Rust point
  time: the call overhead;
- the Dask material sweep (python/examples/dask_sweep.py) on a LocalCluster with 1 and 2
  worker processes.

Usage: python python/bench.py [--vclay target/release/vclay] [--skip-dask]
Run with RAYON_NUM_THREADS unset; the single-thread figures use a subprocess with it set to 1.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import vclay

HERE = Path(__file__).resolve().parent


def bench_surface():
    n = 16
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x, y = i / (n - 1), j / (n - 1)
    pts = np.stack([x, y, 0.2 * np.sin(7 * x) * np.cos(5 * y)], axis=-1)
    w = 1.0 + 0.25 * ((i * n + j) % 5)
    k = np.concatenate([np.zeros(4), np.arange(1, n - 3) / (n - 3), np.ones(4)])
    return vclay.Surface((3, 3), (k, k), pts, w)


def best(f, budget=2.0, runs=3):
    t0, out, k = time.perf_counter(), float("inf"), 0
    while k < runs or time.perf_counter() - t0 < budget:
        t = time.perf_counter()
        f()
        out = min(out, time.perf_counter() - t)
        k += 1
    return out


def python_eval():
    s = bench_surface()
    rng = np.random.default_rng(1)
    uv = rng.uniform(0, 1, (1_000_000, 2))
    batch = best(lambda: s.evaluate(uv))
    u = np.linspace(0, 1, 1000)
    grid = best(lambda: s.evaluate_grid(u, u))
    buf = np.empty((1000, 1000, 3))
    grid_out = best(lambda: s.evaluate_grid(u, u, out=buf))
    few = uv[:100_000].tolist()
    point = s.point

    def loop():
        for a, b in few:
            point(a, b)

    per_call = best(loop, budget=2.0) / len(few)

    def empty():
        for a, b in few:
            pass

    loop_only = best(empty, budget=1.0) / len(few)
    return {
        "batched_points_per_second": 1e6 / batch,
        "grid_points_per_second": 1e6 / grid,
        "grid_out_points_per_second": 1e6 / grid_out,
        "point_call_ns": per_call * 1e9,
        "python_loop_ns": loop_only * 1e9,
    }


def dask_sweep(workers, values, steps):
    sys.path.insert(0, str(HERE / "examples"))
    import dask_sweep as ds

    client = ds.local_client(workers, rayon_threads=1)
    try:
        client.run(lambda: None)
        ds.sweep(client, ds.SCENARIO, values[:workers], 1)  # warm: import vclay on workers
        t = time.perf_counter()
        ds.sweep(client, ds.SCENARIO, values, steps)
        return time.perf_counter() - t
    finally:
        client.close()
        client.cluster.close()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vclay", default=str(HERE.parent / "target" / "release" / "vclay"))
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--python-only", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.python_only:
        print(json.dumps(python_eval()))
        return
    out = {"cpus": os.cpu_count()}
    if Path(args.vclay).exists():
        out["rust"] = json.loads(
            subprocess.run([args.vclay, "bench", "--seconds", "2"], check=True,
                           capture_output=True, text=True).stdout)
    out["python_all_threads"] = python_eval()
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    out["python_1_thread"] = json.loads(subprocess.run(
        [sys.executable, __file__, "--python-only"], check=True, capture_output=True,
        text=True, env=env).stdout)
    if "rust" in out:
        r = out["rust"]
        rust_point_rate = 1e9 / r["surface_point_ns"]
        out["ratios"] = {
            "rust_scattered_1_thread_over_python_batched_1_thread":
                rust_point_rate / out["python_1_thread"]["batched_points_per_second"],
            "rust_grid_1_thread_over_python_grid_1_thread":
                r["surface_grid_points_per_second_1_thread"]
                / out["python_1_thread"]["grid_points_per_second"],
            "rust_grid_all_over_python_grid_all":
                r["surface_grid_points_per_second_all_threads"]
                / out["python_all_threads"]["grid_points_per_second"],
            "rust_grid_1_thread_over_python_grid_out_1_thread":
                r["surface_grid_points_per_second_1_thread"]
                / out["python_1_thread"]["grid_out_points_per_second"],
            "rust_grid_all_over_python_grid_out_all":
                r["surface_grid_points_per_second_all_threads"]
                / out["python_all_threads"]["grid_out_points_per_second"],
            "point_call_overhead_ns":
                out["python_1_thread"]["point_call_ns"] - r["surface_point_ns"],
        }
    if not args.skip_dask:
        values = [40.0, 60.0, 80.0, 100.0, 120.0, 140.0, 160.0, 180.0]
        steps = 150
        out["dask_sweep"] = {
            "jobs": len(values),
            "steps_per_job": steps,
            "seconds_1_worker": dask_sweep(1, values, steps),
            "seconds_2_workers": dask_sweep(2, values, steps),
        }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()

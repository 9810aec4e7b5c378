"""A material sweep over a scenario, fanned out over Dask (issue 21).

Each job loads the scenario (by default the rope-pulled cube of
`subdivision-solids-journal.txt` Fig 7, `examples/scenarios/fig07_rope_cube.toml`), sets the
edge spring stiffness, runs a number of steps and returns the final data points and energy.
The jobs are independent, so they are mapped over a Dask cluster and gathered; the results are
the same bits as the serial loop (`serial`), because each job is the same deterministic
computation in whichever process it runs.

Run here (a LocalCluster of worker processes, one thread each):

    python python/examples/dask_sweep.py --workers 2

Run on a real cluster: start a scheduler (`dask scheduler`) and workers on each machine
(`dask worker tcp://SCHEDULER:8786 --nthreads 1 --nworkers N`, with vclay installed in each
worker's environment; `RAYON_NUM_THREADS=T` with N x T = cores), make the
scenario file readable at the same path on every worker (or pass its text and write it to a
temporary file in `simulate`), then:

    python python/examples/dask_sweep.py --scheduler tcp://SCHEDULER:8786

The same `sweep` function runs against either: only the `Client` differs.
"""

import argparse
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "examples" / "scenarios" / "fig07_rope_cube.toml"


def simulate(scenario, stiffness, steps):
    """One job: the scenario with `edge_stiffness = stiffness`, run for `steps` steps."""
    import vclay

    s = vclay.Session.load(scenario)
    s.apply({"action": "set", "name": "edge_stiffness", "value": float(stiffness)})
    s.step(steps)
    return {
        "stiffness": float(stiffness),
        "energy": s.energy()["total"],
        "data_points": s.data_points(),
    }


def serial(scenario, values, steps):
    """The reference: the same jobs one after another in this process."""
    return [simulate(scenario, v, steps) for v in values]


def sweep(client, scenario, values, steps):
    """Maps the jobs over the cluster behind `client` and gathers the results in order."""
    n = len(values)
    futures = client.map(simulate, [str(scenario)] * n, list(values), [steps] * n, pure=False)
    return client.gather(futures)


def local_client(workers, rayon_threads=None):
    """A LocalCluster of `workers` processes with one Dask thread each; `rayon_threads` sets
    `RAYON_NUM_THREADS` in the workers (vclay's own threads per process; default: inherited).

    The dynamic solids split their sums by thread, so results are bit for bit those of the
    serial loop when both run with the same number of threads, and equal to rounding otherwise.
    """
    from dask.distributed import Client, LocalCluster

    env = {} if rayon_threads is None else {"RAYON_NUM_THREADS": str(rayon_threads)}
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        env=env,
    )
    return Client(cluster)


def same(a, b):
    return all(
        x["stiffness"] == y["stiffness"]
        and x["energy"] == y["energy"]
        and np.array_equal(x["data_points"], y["data_points"])
        for x, y in zip(a, b)
    ) and len(a) == len(b)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786)")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    ap.add_argument("--scenario", default=str(SCENARIO))
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--values", type=float, nargs="+", default=[40, 60, 80, 100, 120, 140, 160, 180])
    ap.add_argument("--rayon-threads", type=int, help="RAYON_NUM_THREADS of the local workers")
    ap.add_argument("--check", action="store_true", help="also run the serial loop and compare")
    args = ap.parse_args()

    from dask.distributed import Client

    client = Client(args.scheduler) if args.scheduler else local_client(args.workers, args.rayon_threads)
    with client:
        client.run(lambda: None)  # workers up before timing
        t = time.perf_counter()
        results = sweep(client, args.scenario, args.values, args.steps)
        dt = time.perf_counter() - t
    for r in results:
        print(f"edge_stiffness {r['stiffness']:8.2f}: energy {r['energy']:.6g}")
    print(f"{len(results)} jobs in {dt:.2f} s")
    if args.check:
        ok = same(results, serial(args.scenario, args.values, args.steps))
        print("equal to the serial loop:", ok)
        raise SystemExit(0 if ok else 1)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""External check of vclay's geomdl JSON exchange with NURBS-Python (geomdl) itself.

For each vclay model: `vclay convert MODEL.json X.geomdl.json`, import with
`geomdl.exchange.import_json`, evaluate every curve, surface and volume there and compare with
`vclay eval` at the same points; then export from geomdl (`exchange.export_json`), convert back
with `vclay convert Y.geomdl.json Z.json` and compare `vclay eval` on Z with the original.
geomdl normalizes knot vectors to [0, 1], so its parameters are mapped affinely from vclay's.
Fails if a point differs by more than 1e-9 x max(1, model size).

Usage: python check_geomdl.py VCLAY_BINARY WORK_DIR MODEL.json...   (see bench/check_geomdl.sh)
"""

import json
import subprocess
import sys
from pathlib import Path

from geomdl import exchange, multi

TOL = 1e-9
N = 6


def run(*args):
    return subprocess.run(list(args), check=True, capture_output=True, text=True).stdout


def vclay_eval(vclay, model, entity, params, work):
    pfile = work / "params.json"
    pfile.write_text(json.dumps(params))
    out = run(vclay, "eval", str(model), "--params", str(pfile), "--entity", str(entity))
    return json.loads(out)["points"]


def linspace(a, b, n):
    return [a + (b - a) * k / (n - 1) for k in range(n)]


def entities(model):
    doc = json.loads(Path(model).read_text())
    ents = doc["entities"] if isinstance(doc, dict) and "entities" in doc else doc
    return ents if isinstance(ents, list) else [ents]


def domains(e):
    deg = e["degree"] if isinstance(e["degree"], list) else [e["degree"]]
    kvs = e["knots"] if isinstance(e["degree"], list) else [e["knots"]]
    return [(kv[p], kv[len(kv) - p - 1]) for kv, p in zip(kvs, deg)]


def grid(doms):
    axes = [linspace(a, b, N if len(doms) > 1 else 4 * N) for a, b in doms]
    pts = [[]]
    for ax in axes:
        pts = [p + [x] for p in pts for x in ax]
    return pts


def check(vclay, model, work):
    stem = Path(model).stem
    g1 = work / f"{stem}.geomdl.json"
    run(vclay, "convert", str(model), str(g1))
    shapes = exchange.import_json(str(g1))
    g2 = work / f"{stem}.from-geomdl.geomdl.json"
    container = {1: multi.CurveContainer, 2: multi.SurfaceContainer, 3: multi.VolumeContainer}
    exchange.export_json(container[shapes[0].pdimension](shapes), str(g2))
    back = work / f"{stem}.back.json"
    run(vclay, "convert", str(g2), str(back))
    worst_eval = worst_trip = 0.0
    size = 1.0
    for i, (e, shape) in enumerate(zip(entities(model), shapes)):
        doms = domains(e)
        params = grid(doms)
        ref = vclay_eval(vclay, model, i, params, work)
        unit = [[(x - a) / (b - a) for x, (a, b) in zip(p, doms)] for p in params]
        got = [shape.evaluate_single(u[0] if len(u) == 1 else tuple(u)) for u in unit]
        trip = vclay_eval(vclay, back, i, [u for u in unit], work)
        for r, g, t in zip(ref, got, trip):
            size = max(size, max(abs(x) for x in r))
            worst_eval = max(worst_eval, max(abs(x - y) for x, y in zip(r, g)))
            worst_trip = max(worst_trip, max(abs(x - y) for x, y in zip(r, t)))
    tol = TOL * size
    ok = worst_eval <= tol and worst_trip <= tol
    print(f"{'ok' if ok else 'FAIL'} {Path(model).name}: {len(shapes)} shapes; geomdl vs vclay "
          f"{worst_eval:.2e}, round trip through geomdl {worst_trip:.2e} (tolerance {tol:.1e})")
    return ok


def main():
    vclay, work = sys.argv[1], Path(sys.argv[2])
    work.mkdir(parents=True, exist_ok=True)
    ok = all([check(vclay, m, work) for m in sys.argv[3:]])
    print("check_geomdl:", "passed" if ok else "FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()

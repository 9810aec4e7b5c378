#!/usr/bin/env python3
"""External check of vclay's STEP and IGES export with OpenCASCADE (cadquery-ocp).

For each model (curves, surfaces, a volume; rational and not; repeated interior knots), the
script runs `vclay convert MODEL.json MODEL.step` (or `.igs`), loads the file with
OpenCASCADE's STEPControl_Reader (or IGESControl_Reader), evaluates every curve and surface OpenCASCADE built at a grid of parameters,
and compares with `vclay eval` at the same parameters. It fails if a file does not load, if a
B-spline comes back as another kind of geometry, or if a point differs by more than
1e-9 x max(1, model size).

Usage: python check_step.py VCLAY_BINARY WORK_DIR step|iges MODEL.json...
Run through bench/check_step.sh, which finds or installs cadquery-ocp and says when it skips.
"""

import json
import subprocess
import sys
from pathlib import Path

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.IFSelect import IFSelect_RetDone
from OCP.IGESControl import IGESControl_Reader
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

TOL = 1e-9
N = 7  # samples per parametric axis


def vclay_eval(vclay, model, entity, params, work):
    pfile = work / "params.json"
    pfile.write_text(json.dumps(params))
    out = subprocess.run(
        [vclay, "eval", str(model), "--params", str(pfile), "--entity", str(entity)],
        check=True, capture_output=True, text=True,
    ).stdout
    return json.loads(out)["points"]


def load(path, fmt):
    r = STEPControl_Reader() if fmt == "step" else IGESControl_Reader()
    if r.ReadFile(str(path)) != IFSelect_RetDone:
        raise SystemExit(f"FAIL {path}: OpenCASCADE cannot read the file")
    r.TransferRoots()
    shape = r.OneShape()
    faces, edges = [], []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        faces.append(BRep_Tool.Surface_s(TopoDS.Face(ex.Current())))
        ex.Next()
    ex = TopExp_Explorer(shape, TopAbs_EDGE)
    while ex.More():
        edges.append(BRepAdaptor_Curve(TopoDS.Edge(ex.Current())))
        ex.Next()
    return faces, edges


def linspace(a, b, n):
    return [a + (b - a) * k / (n - 1) for k in range(n)]


def domain(knots, degree):
    return knots[degree], knots[len(knots) - degree - 1]


def check_model(vclay, model, work, fmt):
    doc = json.loads(model.read_text())
    ents = doc["entities"] if isinstance(doc, dict) and "entities" in doc else doc
    ents = ents if isinstance(ents, list) else [ents]
    ext = ".step" if fmt == "step" else ".igs"
    step = work / (model.stem + ext)
    subprocess.run([vclay, "convert", str(model), str(step)], check=True, capture_output=True)
    faces, edges = load(step, fmt)
    size = 1.0
    worst = 0.0
    fi = ei = 0
    for i, e in enumerate(ents):
        kind = e["type"]
        if kind == "nurbs-curve":
            a, b = domain(e["knots"], e["degree"])
            params = [[u] for u in linspace(a, b, 4 * N)]
            ref = vclay_eval(vclay, model, i, params, work)
            # OpenCASCADE's IGES reader splits a curve at C0 knots into several edges that
            # keep the curve's parameters: gather the edges until the domain's end.
            segs = []
            while True:
                segs.append(edges[ei])
                ei += 1
                if abs(segs[-1].LastParameter() - b) <= 1e-12 * (1 + abs(b)):
                    break
            def seg(u):
                return next(c for c in segs if c.FirstParameter() <= u <= c.LastParameter())
            got = [seg(p[0]).Value(p[0]).Coord() for p in params]
        elif kind == "nurbs-surface":
            (a, b), (c0, c1) = (domain(e["knots"][k], e["degree"][k]) for k in range(2))
            params = [[u, v] for u in linspace(a, b, N) for v in linspace(c0, c1, N)]
            ref = vclay_eval(vclay, model, i, params, work)
            s = faces[fi]
            fi += 1
            if s.DynamicType().Name() != "Geom_BSplineSurface":
                raise SystemExit(f"FAIL {model.name} entity {i}: came back as {s.DynamicType().Name()}")
            rational = any(w != 1 for row in e.get("weights", [[1]]) for w in row)
            if rational and not (s.IsURational() or s.IsVRational()):
                raise SystemExit(f"FAIL {model.name} entity {i}: weights lost")
            got = [s.Value(u, v).Coord() for u, v in params]
        else:  # volume: six boundary faces, u=min, u=max, v=min, v=max, w=min, w=max
            doms = [domain(e["knots"][k], e["degree"][k]) for k in range(3)]
            ref, got = [], []
            for axis in range(3):
                a1, a2 = [k for k in range(3) if k != axis]
                for side in range(2):
                    s = faces[fi]
                    fi += 1
                    for p in linspace(*doms[a1], N):
                        for q in linspace(*doms[a2], N):
                            t = [0.0, 0.0, 0.0]
                            t[axis] = doms[axis][side]
                            t[a1], t[a2] = p, q
                            ref.append(t)
                            got.append(s.Value(p, q).Coord())
            ref = vclay_eval(vclay, model, i, ref, work)
        for r in ref:
            size = max(size, max(abs(x) for x in r))
        for r, g in zip(ref, got):
            worst = max(worst, max(abs(x - y) for x, y in zip(r, g)))
    tol = TOL * size
    status = "ok" if worst <= tol else "FAIL"
    print(f"{status} {fmt} {model.name}: {len(faces)} faces, {len(edges)} edges, "
          f"largest difference from vclay eval {worst:.2e} (tolerance {tol:.1e})")
    return worst <= tol


def main():
    vclay, work, fmt = sys.argv[1], Path(sys.argv[2]), sys.argv[3]
    work.mkdir(parents=True, exist_ok=True)
    ok = all([check_model(vclay, Path(m), work, fmt) for m in sys.argv[4:]])
    print(f"check_step ({fmt}):", "passed" if ok else "FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""External check of vclay's B-rep export (STEP solids and shells; IGES) with OpenCASCADE.

For each model JSON given, the script runs `vclay convert MODEL.json MODEL.step` (or `.igs`),
loads the file with OpenCASCADE (STEPControl_Reader / IGESControl_Reader) and checks:

- BRepCheck_Analyzer finds the shape valid;
- a model whose surfaces close up (EXPECT "solid") is exactly one TopAbs_SOLID whose shell is
  closed (BRep_Tool.IsClosed), and its volume (BRepGProp.VolumeProperties, adaptive, 1e-10)
  matches vclay's volume to 1e-6 relative;
- an open model (EXPECT "open") has no solid and one open shell per surface; EXPECT "auto"
  takes what vclay wrote (a solid when the file holds MANIFOLD_SOLID_BREP or entity 186);
- the face orientations as written in the file (STEP: ADVANCED_FACE same_sense; IGES: the
  514 shell's orientation flags) point outward: at the middle of each face, a point a little
  along the written normal is outside the solid and a point a little against it inside
  (BRepClass3d_SolidClassifier). OpenCASCADE's reader repairs solids that are inside out, so the
  volume alone would not catch a wrong orientation.

vclay's volume is computed here, independently of vclay and of OpenCASCADE, from the model JSON:
for a surface, the divergence theorem V = |1/3 int int S . (S_u x S_v) du dv| with 24-point
Gauss-Legendre quadrature on every knot span; for a B-spline volume, int int int det J du dv dw
with 10-point Gauss-Legendre per span (NURBS evaluated with the Cox-de Boor recursion and the
quotient rule for rational derivatives, Piegl & Tiller eqs 2.5, 2.9, 4.8). Both are printed.

A MODEL may be a subdivision-solid lattice (.ovm): vclay writes the bicubic patches of its
boundary limit surface joined into one shell, and the volume is that of the same patches
(`vclay convert LATTICE.ovm PATCHES.json`; the divergence theorem summed over the patches).

Usage: python check_brep.py VCLAY_BINARY WORK_DIR step|iges MODEL.json|LATTICE.ovm:solid|open|auto ...
Run through bench/check_step.sh, which finds or installs cadquery-ocp and says when it skips.
"""

import json
import math
import subprocess
import sys
from pathlib import Path

from OCP.BRep import BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepClass3d import BRepClass3d_SolidClassifier
from OCP.gp import gp_Pnt, gp_Vec
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.IGESControl import IGESControl_Reader
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_FACE, TopAbs_IN, TopAbs_OUT, TopAbs_SHELL, TopAbs_SOLID
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

RTOL = 1e-6


def gauss_legendre(n):
    """Nodes and weights on [-1, 1] (Newton iteration on P_n)."""
    xs, ws = [], []
    for i in range(n):
        x = math.cos(math.pi * (i + 0.75) / (n + 0.5))
        for _ in range(100):
            p0, p1 = 1.0, x
            for k in range(2, n + 1):
                p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
            dp = n * (x * p1 - p0) / (x * x - 1)
            dx = p1 / dp
            x -= dx
            if abs(dx) < 1e-16:
                break
        xs.append(x)
        ws.append(2 / ((1 - x * x) * dp * dp))
    return xs, ws


def basis(knots, p, u):
    """Span index i and the values and first derivatives of N_{i-p..i, p}(u)."""
    n = len(knots) - p - 1
    if u >= knots[n]:
        i = n - 1
        while knots[i] == knots[i + 1]:
            i -= 1
    else:
        i = p
        while not (knots[i] <= u < knots[i + 1]):
            i += 1

    def values(deg):
        N = [1.0] + [0.0] * deg
        left, right = [0.0] * (deg + 1), [0.0] * (deg + 1)
        for j in range(1, deg + 1):
            left[j] = u - knots[i + 1 - j]
            right[j] = knots[i + j] - u
            saved = 0.0
            for r in range(j):
                t = N[r] / (right[r + 1] + left[j - r])
                N[r] = saved + right[r + 1] * t
                saved = left[j - r] * t
            N[j] = saved
        return N

    N = values(p)
    if p == 0:
        return i, N, [0.0]
    lower = values(p - 1)  # N_{i-p+1..i, p-1}
    dN = []
    for r in range(p + 1):
        k = i - p + r  # global index of N_{k,p}
        a = lower[r - 1] / (knots[k + p] - knots[k]) if r >= 1 and knots[k + p] > knots[k] else 0.0
        b = lower[r] / (knots[k + p + 1] - knots[k + 1]) if r <= p - 1 and knots[k + p + 1] > knots[k + 1] else 0.0
        dN.append(p * (a - b))
    return i, N, dN


def spans(knots, p):
    lo, hi = knots[p], knots[len(knots) - p - 1]
    d = sorted(set(k for k in knots if lo <= k <= hi))
    return list(zip(d[:-1], d[1:]))


def entities(path):
    doc = json.loads(Path(path).read_text())
    ents = doc["entities"] if isinstance(doc, dict) and "entities" in doc else doc
    return ents if isinstance(ents, list) else [ents]


def rational(values):
    """(point, first partials) from homogeneous values [A, A_1, A_2, ...] (4-vectors)."""
    w = values[0][3]
    s = [values[0][k] / w for k in range(3)]
    ders = [[(d[k] - d[3] * s[k]) / w for k in range(3)] for d in values[1:]]
    return s, ders


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def surface_volume(e, n=24):
    (p, q), (U, V) = e["degree"], e["knots"]
    P = e["control_points"]
    W = e.get("weights") or [[1.0] * len(r) for r in P]
    xs, ws = gauss_legendre(n)
    total = 0.0
    for a, b in spans(U, p):
        for xu, wu in zip(xs, ws):
            u = 0.5 * (a + b) + 0.5 * (b - a) * xu
            iu, Nu, dNu = basis(U, p, u)
            for c, d in spans(V, q):
                for xv, wv in zip(xs, ws):
                    v = 0.5 * (c + d) + 0.5 * (d - c) * xv
                    iv, Nv, dNv = basis(V, q, v)
                    acc = [[0.0] * 4 for _ in range(3)]
                    for r in range(p + 1):
                        for t in range(q + 1):
                            pt, w = P[iu - p + r][iv - q + t], W[iu - p + r][iv - q + t]
                            h = (pt[0] * w, pt[1] * w, pt[2] * w, w)
                            for k, f in enumerate((Nu[r] * Nv[t], dNu[r] * Nv[t], Nu[r] * dNv[t])):
                                for m in range(4):
                                    acc[k][m] += f * h[m]
                    s, (su, sv) = rational(acc)
                    jac = 0.25 * (b - a) * (d - c) * wu * wv
                    total += jac * dot(s, cross(su, sv))
    return total / 3.0


def volume_volume(e, n=10):
    degs, knots = e["degree"], e["knots"]
    P = e["control_points"]
    W = e.get("weights")
    xs, ws = gauss_legendre(n)
    total = 0.0
    s0, s1, s2 = (spans(knots[k], degs[k]) for k in range(3))
    pts = [[(0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w) for a, b in s for x, w in zip(xs, ws)]
           for s in (s0, s1, s2)]
    bases = [[(basis(knots[k], degs[k], t), jw) for t, jw in pts[k]] for k in range(3)]
    p, q, r = degs
    for (iu, Nu, dNu), ju in bases[0]:
        for (iv, Nv, dNv), jv in bases[1]:
            for (iw, Nw, dNw), jw in bases[2]:
                acc = [[0.0] * 4 for _ in range(4)]
                for a in range(p + 1):
                    for b in range(q + 1):
                        for c in range(r + 1):
                            pt = P[iu - p + a][iv - q + b][iw - r + c]
                            w = W[iu - p + a][iv - q + b][iw - r + c] if W else 1.0
                            h = (pt[0] * w, pt[1] * w, pt[2] * w, w)
                            fs = (Nu[a] * Nv[b] * Nw[c], dNu[a] * Nv[b] * Nw[c],
                                  Nu[a] * dNv[b] * Nw[c], Nu[a] * Nv[b] * dNw[c])
                            for k in range(4):
                                for m in range(4):
                                    acc[k][m] += fs[k] * h[m]
                _, (xu, xv, xw) = rational(acc)
                total += ju * jv * jw * dot(xu, cross(xv, xw))
    return abs(total)


def model_volume(path):
    """Surfaces: one closed surface, or patches oriented alike (signed sum); volumes: each."""
    surfaces = sum(surface_volume(e) for e in entities(path) if e["type"] == "nurbs-surface")
    volumes = sum(volume_volume(e) for e in entities(path) if e["type"] == "nurbs-volume")
    return abs(surfaces) + volumes


def subshapes(shape, kind):
    out, ex = [], TopExp_Explorer(shape, kind)
    while ex.More():
        out.append(ex.Current())
        ex.Next()
    return out


def written_senses(path, fmt):
    """Face orientations as written: +1 where the outward normal is S_u x S_v, else -1."""
    text = Path(path).read_text()
    if fmt == "step":
        return [1 if line.rstrip().endswith(".T.);") else -1
                for line in text.splitlines() if "=ADVANCED_FACE(" in line]
    # IGES: join the parameter lines of the 514 shells.
    params = {}
    for line in text.splitlines():
        if len(line) >= 73 and line[72] == "P":
            params.setdefault(int(line[64:72]), []).append(line[:64].strip())
    senses = []
    for lines in params.values():
        tokens = "".join(lines).rstrip(";").split(",")
        if tokens[0] == "514":
            senses += [1 if t == "1" else -1 for t in tokens[3::2]]
    return senses


def orientation_ok(solid, faces, senses, size):
    """Whether each face's written normal points out of the solid at the face's middle."""
    if len(faces) != len(senses):
        return False
    eps = 1e-4 * size
    for face, sense in zip(faces, senses):
        surf = BRep_Tool.Surface_s(TopoDS.Face(face))
        u0, u1, v0, v1 = surf.Bounds()
        p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
        surf.D1(0.5 * (u0 + u1), 0.5 * (v0 + v1), p, du, dv)
        n = du.Crossed(dv)
        n.Normalize()
        n.Multiply(sense * eps)
        outside, inside = p.Translated(n), p.Translated(n.Reversed())
        for q, want in ((outside, TopAbs_OUT), (inside, TopAbs_IN)):
            if BRepClass3d_SolidClassifier(solid, q, 1e-9 * size).State() != want:
                return False
    return True


def check(vclay, work, fmt, model, expect):
    ext = ".step" if fmt == "step" else ".igs"
    out = work / (model.stem + ext)
    subprocess.run([vclay, "convert", str(model), str(out)], check=True, capture_output=True)
    if model.suffix == ".ovm":
        # A subdivision-solid lattice: its limit patches, joined into one shell by vclay; the
        # volume is computed from the same patches as model JSON.
        patches = work / (model.stem + "_patches.json")
        subprocess.run([vclay, "convert", str(model), str(patches)], check=True,
                       capture_output=True)
        model = patches
    if expect == "auto":
        text = out.read_text()
        solid = ("MANIFOLD_SOLID_BREP(" in text if fmt == "step"
                 else any(len(l) >= 73 and l[72] == "D" and l[:8].strip() == "186"
                          for l in text.splitlines()))
        expect = "solid" if solid else "open"
    r = STEPControl_Reader() if fmt == "step" else IGESControl_Reader()
    if r.ReadFile(str(out)) != IFSelect_RetDone:
        print(f"FAIL {fmt} {model.name}: OpenCASCADE cannot read {out}")
        return False
    r.TransferRoots()
    shape = r.OneShape()
    valid = BRepCheck_Analyzer(shape).IsValid()
    solids = subshapes(shape, TopAbs_SOLID)
    shells = subshapes(shape, TopAbs_SHELL)
    faces = subshapes(shape, TopAbs_FACE)
    closed = [BRep_Tool.IsClosed_s(s) for s in shells]
    head = (f"{fmt} {model.name}: valid={valid}, {len(solids)} solid(s), {len(shells)} shell(s) "
            f"(closed: {closed}), {len(faces)} face(s)")
    if expect == "solid":
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(shape, props, 1e-10)
        occ = props.Mass()
        ours = model_volume(model)
        rel = abs(occ - ours) / abs(ours)
        size = max(1.0, ours ** (1 / 3))
        outward = len(solids) == 1 and orientation_ok(solids[0], faces, written_senses(out, fmt), size)
        ok = (valid and len(solids) == 1 and len(shells) == 1 and all(closed) and rel <= RTOL
              and outward)
        print(f"{'ok' if ok else 'FAIL'} {head}; faces written outward: {outward}; volume "
              f"OpenCASCADE {occ:.12g}, vclay {ours:.12g}, relative difference {rel:.1e} "
              f"(tolerance {RTOL:.0e})")
    else:
        n = len(entities(model)) if model.suffix == ".json" else 1
        ok = valid and not solids and len(shells) == n and not any(closed)
        print(f"{'ok' if ok else 'FAIL'} {head}; expected {n} open shell(s), no solid")
    return ok


def main():
    vclay, work, fmt = sys.argv[1], Path(sys.argv[2]), sys.argv[3]
    work.mkdir(parents=True, exist_ok=True)
    results = []
    for arg in sys.argv[4:]:
        path, expect = arg.rsplit(":", 1)
        results.append(check(vclay, work, fmt, Path(path), expect))
    ok = all(results)
    print(f"check_brep ({fmt}):", "passed" if ok else "FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()

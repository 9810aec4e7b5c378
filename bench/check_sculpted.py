#!/usr/bin/env python3
"""External check of issue 30's sculpted round trip with OpenCASCADE.

Makes OpenCASCADE's plate (bench/gen_trimmed_parts.py: a 40 x 30 x 8 box with a hole of
radius 6 and four filleted top edges, 11 trimmed faces), finds its top face in vclay's
numbering (`vclay convert plate.step plate.json`: the face with a hole whose surface lies at
z = 8), and runs a scenario (`vclay run`) that opens the plate as a `cad-part` with that face
sculpted, its boundary fixed (the default), and a rope that pulls the point (8, 15, 8) up for
30 steps; the run writes the part as STEP (`[output] final`). OpenCASCADE reads it back and
the check asks:

- BRepCheck_Analyzer finds the shape valid, and it is exactly one solid of 11 faces;
- its volume changed (grew by more than 1e-4 relative: the face bulges outward);
- every untouched face is identical: for each of the 10 other faces of vclay's own unsculpted
  round trip (`vclay convert plate.step plate_vclay.step`) there is a face of the result with
  the same area (BRepGProp, 1e-12 relative) and the same points (20 x 20 parameter samples of
  the result's face projected onto the reference face's surface: distance below 1e-12 x the
  part's size); and the same against OpenCASCADE's original to the conversion's accuracy
  (area 1e-6, points 1e-9 x size).

Prints one line per check. Usage: python check_sculpted.py VCLAY_BINARY WORK_DIR
Run through bench/check_step.sh, which finds or installs cadquery-ocp and says when it skips.
"""
import json
import subprocess
import sys
from pathlib import Path

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_FACE, TopAbs_SOLID
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

# Against vclay's own unsculpted round trip (`vclay convert plate.step`): the untouched faces
# are written from the same data, so they must agree to rounding.
AREA_RTOL = 1e-12
POINT_RTOL = 1e-12
# Against OpenCASCADE's original: the accuracy of the conversion itself (check_trimmed.py's
# RTOL; a fillet's area comes back to about 8e-9, its trimming pcurves being polylines).
AREA_RTOL_ORIGINAL = 1e-6
POINT_RTOL_ORIGINAL = 1e-9
SIZE = (40.0**2 + 30.0**2 + 8.0**2) ** 0.5


def items(shape, kind):
    out, ex = [], TopExp_Explorer(shape, kind)
    while ex.More():
        out.append(ex.Current())
        ex.Next()
    return out


def read(path):
    r = STEPControl_Reader()
    if r.ReadFile(str(path)) != IFSelect_RetDone:
        raise SystemExit(f"check_sculpted: OpenCASCADE cannot read {path}")
    r.TransferRoots()
    return r.OneShape()


def volume(shape):
    p = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, p, 1e-10)
    return p.Mass()


def area(face):
    p = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, p, 1e-10)
    return p.Mass()


def same_face(f, g, area_rtol, point_rtol):
    """Whether face g (of the result) is face f (of the original): the same area, and g's
    points lie on f's surface (vclay writes every surface as a B-spline, so the surface types
    differ: OpenCASCADE's planes and cylinders come back as their exact B-spline forms)."""
    af, ag = area(f), area(g)
    sg = BRepAdaptor_Surface(g)
    if abs(af - ag) > area_rtol * af:
        return False
    surf = BRep_Tool.Surface_s(f)
    u0, u1, v0, v1 = sg.FirstUParameter(), sg.LastUParameter(), sg.FirstVParameter(), \
        sg.LastVParameter()
    for i in range(20):
        for j in range(20):
            p = sg.Value(u0 + (u1 - u0) * (i + 0.5) / 20, v0 + (v1 - v0) * (j + 0.5) / 20)
            proj = GeomAPI_ProjectPointOnSurf(p, surf)
            if proj.NbPoints() == 0 or proj.LowerDistance() > point_rtol * SIZE:
                return False
    return True


def top_face(model_json):
    """vclay's index of the plate's top face: two loops, surface at z = 8."""
    m = json.loads(model_json.read_text())
    ents = m["entities"]
    for i, f in enumerate(m["shells"][0]["faces"]):
        pts = ents[f["surface"]]["control_points"]
        flat = [p for row in pts for p in row] if isinstance(pts[0][0], list) else pts
        if len(f["loops"]) == 2 and all(abs(p[2] - 8.0) < 1e-9 for p in flat):
            return i
    raise SystemExit("check_sculpted: no top face with a hole at z = 8 in the plate")


def main():
    vclay, work = sys.argv[1], Path(sys.argv[2])
    work.mkdir(parents=True, exist_ok=True)
    gen = Path(__file__).with_name("gen_trimmed_parts.py")
    subprocess.run([sys.executable, str(gen), str(work)], check=True, capture_output=True)
    src = work / "plate.step"
    subprocess.run([vclay, "convert", str(src), str(work / "plate.json"), "-q"], check=True)
    face = top_face(work / "plate.json")
    scenario = work / "sculpt_plate.toml"
    scenario.write_text(
        "# Issue 30: OpenCASCADE's plate, its top face pulled up by a rope, boundary fixed.\n"
        f'[model]\nkind = "cad-part"\nfile = "plate.step"\nface = {face}\n\n'
        "[simulation]\nsteps = 30\n\n"
        '[output]\nfinal = "sculpted.step"\n\n'
        '[[timeline]]\nat = 0.0\naction = "rope"\nname = "pull"\n'
        "from = [8.0, 15.0, 8.0]\nvelocity = [0.0, 0.0, 20.0]\nstiffness = 200.0\n")
    out = work / "sculpted"
    subprocess.run([vclay, "run", str(scenario), "--out", str(out)], check=True,
                   capture_output=True)
    ref, res = read(src), read(out / "sculpted.step")
    failures = 0

    def check(ok, what):
        nonlocal failures
        failures += not ok
        print(f"check_sculpted: {what}: {'ok' if ok else 'FAILED'}")

    valid = BRepCheck_Analyzer(res).IsValid()
    solids, faces = len(items(res, TopAbs_SOLID)), items(res, TopAbs_FACE)
    check(valid and solids == 1 and len(faces) == 11,
          f"valid {valid}, {solids} solid(s), {len(faces)}/11 faces")
    v0, v1 = volume(ref), volume(res)
    check(v1 > v0 * (1 + 1e-4), f"volume {v0:.10g} -> {v1:.10g} ({(v1 - v0) / v0:+.3e})")
    results = [TopoDS.Face(f) for f in faces]
    plain = work / "plate_vclay.step"
    subprocess.run([vclay, "convert", str(src), str(plain), "-q"], check=True)
    for name, ref_shape, area_rtol, point_rtol in (
            ("vclay's unsculpted round trip", read(plain), AREA_RTOL, POINT_RTOL),
            ("OpenCASCADE's original", ref, AREA_RTOL_ORIGINAL, POINT_RTOL_ORIGINAL)):
        unmatched = list(results)
        same = 0
        for f in [TopoDS.Face(f) for f in items(ref_shape, TopAbs_FACE)]:
            for g in unmatched:
                if same_face(f, g, area_rtol, point_rtol):
                    unmatched.remove(g)
                    same += 1
                    break
        check(same == 10 and len(unmatched) == 1,
              f"{same}/10 untouched faces identical to {name} (area to {area_rtol:g}, points "
              f"to {point_rtol:g} x size); {len(unmatched)} face(s) changed")
    if failures:
        raise SystemExit(f"check_sculpted: {failures} failure(s)")
    print("check_sculpted: all passed")


main()

"""Writes IGES files of analytic and swept shapes with OpenCASCADE (cadquery-ocp) in its
default face mode, which uses the IGES entities vclay reads since session 9 besides 126/128:
planes (108) bounded through trimmed surfaces (144/142/102), surfaces of revolution (120) of
lines (110), circular arcs (100) and B-splines (126), tabulated cylinders (122), and
transformation matrices (124), chained for a moved shape. For each file, OpenCASCADE reads it
back and records per face the surface type, its tight bounding box, and points of the face's
(untrimmed) surface at seeded random parameters inside the face's parameter box
(occ_iges_points.json), for crates/vclay-io/tests/cad_read.rs.

Run once by hand (not in CI: the wheel is large):
    python3 -m venv /tmp/occ && /tmp/occ/bin/pip install cadquery-ocp
    /tmp/occ/bin/python bench/gen_iges_analytic.py crates/vclay-io/tests/data/cad
"""
import collections
import json
import random
import sys

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_Transform
from OCP.BRepPrimAPI import (BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCone,
                             BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakePrism,
                             BRepPrimAPI_MakeRevol, BRepPrimAPI_MakeSphere,
                             BRepPrimAPI_MakeTorus)
from OCP.BRepTools import BRepTools
from OCP.Bnd import Bnd_Box
from OCP.Geom import Geom_BSplineCurve
from OCP.IFSelect import IFSelect_RetDone
from OCP.IGESControl import IGESControl_Controller, IGESControl_Reader, IGESControl_Writer
from OCP.OCP import collections as col
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec

out = sys.argv[1]
rng = random.Random(9)


def profile():
    """A planar cubic B-spline in the xz plane, off the z axis."""
    pts = col.Array1_gp_Pnt(1, 5)
    for i, (x, z) in enumerate([(1.0, 0.0), (1.6, 0.5), (0.8, 1.2), (1.4, 1.9), (1.0, 2.5)]):
        pts.SetValue(i + 1, gp_Pnt(x, 0.0, z))
    knots = col.Array1_double(1, 3)
    mults = col.Array1_int(1, 3)
    for i, (k, m) in enumerate([(0.0, 4), (0.5, 1), (1.0, 4)]):
        knots.SetValue(i + 1, k)
        mults.SetValue(i + 1, m)
    return Geom_BSplineCurve(pts, knots, mults, 3)


turn = gp_Trsf()
turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(1, 1, 0)), 0.7)
turn.SetTranslationPart(gp_Vec(3, -2, 1))
edge = BRepBuilderAPI_MakeEdge(profile()).Edge()
shapes = {
    "iges_cylinder": BRepPrimAPI_MakeCylinder(1.5, 4.0).Shape(),
    "iges_sphere": BRepPrimAPI_MakeSphere(2.0).Shape(),
    "iges_cone": BRepPrimAPI_MakeCone(2.0, 0.5, 3.0).Shape(),
    "iges_torus": BRepPrimAPI_MakeTorus(3.0, 1.0).Shape(),
    "iges_box_turned": BRepBuilderAPI_Transform(BRepPrimAPI_MakeBox(1, 2, 3).Shape(), turn,
                                                True).Shape(),
    "iges_cylinder_moved": BRepPrimAPI_MakeCylinder(1.5, 4.0).Shape().Moved(
        TopLoc_Location(turn)),
    "iges_revolved_bspline": BRepPrimAPI_MakeRevol(edge, gp_Ax1(gp_Pnt(0, 0, 0),
                                                                gp_Dir(0, 0, 1)), 4.0).Shape(),
    "iges_extruded_bspline": BRepPrimAPI_MakePrism(edge, gp_Vec(0.3, 2.0, 0.4)).Shape(),
}

report = {}
for name, shape in shapes.items():
    path = f"{out}/{name}.igs"
    IGESControl_Controller.Init_s()
    w = IGESControl_Writer("MM", 0)
    w.AddShape(shape)
    w.ComputeModel()
    assert w.Write(path)
    lines = [l for l in open(path) if len(l) >= 73 and l[72] == "D"]
    types = collections.Counter(int(lines[k][0:8]) for k in range(0, len(lines), 2))
    r = IGESControl_Reader()
    assert r.ReadFile(path) == IFSelect_RetDone
    r.TransferRoots()
    back = r.OneShape()
    faces = []
    ex = TopExp_Explorer(back, TopAbs_FACE)
    while ex.More():
        f = TopoDS.Face(ex.Current())
        s = BRep_Tool.Surface_s(f)
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f)
        pts = []
        for _ in range(8):
            p = s.Value(rng.uniform(u0, u1), rng.uniform(v0, v1))
            pts.append([p.X(), p.Y(), p.Z()])
        box = Bnd_Box()
        BRepBndLib.AddOptimal_s(f, box, False, False)
        faces.append({"type": str(BRepAdaptor_Surface(f).GetType()).split(".")[-1],
                      "box": [box.CornerMin().X(), box.CornerMin().Y(), box.CornerMin().Z(),
                              box.CornerMax().X(), box.CornerMax().Y(), box.CornerMax().Z()],
                      "points": pts})
        ex.Next()
    report[name] = {"entity_types": {str(k): v for k, v in sorted(types.items())},
                    "faces": faces}
    print(name, dict(types), len(faces), "faces")
json.dump(report, open(f"{out}/occ_iges_points.json", "w"), indent=1)

"""Writes the STEP and IGES test files of crates/vclay-io/tests/data/cad with OpenCASCADE
(the PyPI package cadquery-ocp), and OpenCASCADE's own evaluation of what it reads back from
them at seeded random parameters (occ_points.json), for crates/vclay-io/tests/cad_read.rs.

Run once by hand (not in CI: the wheel is large):
    python3 -m venv /tmp/occ && /tmp/occ/bin/pip install cadquery-ocp
    /tmp/occ/bin/python bench/gen_cad_test_files.py crates/vclay-io/tests/data/cad
"""
import json
import random
import sys

from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import (BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace,
                                BRepBuilderAPI_NurbsConvert)
from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakeTorus
from OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface
from OCP.GeomAdaptor import GeomAdaptor_Curve
from OCP.IFSelect import IFSelect_RetDone
from OCP.IGESControl import IGESControl_Controller, IGESControl_Reader, IGESControl_Writer
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer
from OCP.OCP import collections as col
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
from OCP.gp import gp_Pnt

out = sys.argv[1]
rng = random.Random(20)


def arr1(vals, cls=col.Array1_double):
    a = cls(1, len(vals))
    for i, v in enumerate(vals):
        a.SetValue(i + 1, v)
    return a


def curve():
    """A non-rational cubic with an interior double knot, non-uniform spacing."""
    pts = col.Array1_gp_Pnt(1, 7)
    for i, (x, y, z) in enumerate([(0, 0, 0), (1, 2, 0.5), (2.5, 2, 1), (3, 0.5, 0),
                                   (4, -1, -0.5), (5.5, 0, 0.25), (6, 1.5, 1)]):
        pts.SetValue(i + 1, gp_Pnt(x, y, z))
    knots = arr1([0.0, 0.3, 0.55, 1.0])
    mults = arr1([4, 1, 2, 4], col.Array1_int)
    return Geom_BSplineCurve(pts, knots, mults, 3)


def rational_surface():
    """Degree (2, 3) with weights, 4 x 5 poles, non-uniform knots."""
    poles = col.Array2_gp_Pnt(1, 4, 1, 5)
    w = col.Array2_double(1, 4, 1, 5)
    for i in range(4):
        for j in range(5):
            poles.SetValue(i + 1, j + 1, gp_Pnt(i * 1.0, j * 0.8, 0.3 * ((i - 1.5) ** 2 - (j - 2) ** 2)))
            w.SetValue(i + 1, j + 1, 1.0 + 0.25 * ((i + 2 * j) % 3))
    uk, um = arr1([0.0, 0.4, 1.0]), arr1([3, 1, 3], col.Array1_int)
    vk, vm = arr1([-1.0, 0.5, 2.0]), arr1([4, 1, 4], col.Array1_int)
    return Geom_BSplineSurface(poles, w, uk, vk, um, vm, 2, 3)


def nurbs(shape):
    return BRepBuilderAPI_NurbsConvert(shape, True).Shape()


shapes = {
    "curve": BRepBuilderAPI_MakeEdge(curve()).Edge(),
    "rational_surface": BRepBuilderAPI_MakeFace(rational_surface(), 1e-7).Face(),
    "torus": nurbs(BRepPrimAPI_MakeTorus(3.0, 1.0).Shape()),
    "cylinder_solid": nurbs(BRepPrimAPI_MakeCylinder(1.0, 2.0).Shape()),
}


def write_step(shape, path):
    w = STEPControl_Writer()
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    w.Transfer(shape, STEPControl_AsIs)
    assert w.Write(path) == IFSelect_RetDone


def write_iges(shape, path):
    IGESControl_Controller.Init_s()
    w = IGESControl_Writer("MM", 0)  # faces as trimmed surfaces (144) over 128, curves 126
    w.AddShape(shape)
    w.ComputeModel()
    assert w.Write(path)


def read(path):
    r = STEPControl_Reader() if path.endswith(".step") else IGESControl_Reader()
    assert r.ReadFile(path) == IFSelect_RetDone
    r.TransferRoots()
    return r.OneShape()


def sample_surface(s):
    s = Geom_BSplineSurface.DownCast(s) if hasattr(Geom_BSplineSurface, "DownCast") else s
    u0, u1, v0, v1 = s.Bounds()
    params, points = [], []
    for _ in range(5):
        u, v = rng.uniform(u0, u1), rng.uniform(v0, v1)
        p = s.Value(u, v)
        params.append([u, v])
        points.append([p.X(), p.Y(), p.Z()])
    p0 = s.Pole(1, 1)
    return {"kind": "surface", "dims": [s.NbUPoles(), s.NbVPoles()],
            "first_pole": [p0.X(), p0.Y(), p0.Z()], "params": params, "points": points}


def sample_curve(c):
    u0, u1 = c.FirstParameter(), c.LastParameter()
    params, points = [], []
    for _ in range(5):
        u = rng.uniform(u0, u1)
        p = c.Value(u)
        params.append([u])
        points.append([p.X(), p.Y(), p.Z()])
    p0 = c.Pole(1)
    return {"kind": "curve", "dims": [c.NbPoles()], "first_pole": [p0.X(), p0.Y(), p0.Z()],
            "params": params, "points": points}


report = {}
for name, shape in shapes.items():
    for ext, writer in ((".step", write_step), (".igs", write_iges)):
        path = f"{out}/{name}{ext}"
        writer(shape, path)
        back = read(path)
        recs = []
        ex = TopExp_Explorer(back, TopAbs_FACE)
        while ex.More():
            surf = BRep_Tool.Surface_s(TopoDS.Face(ex.Current()))
            recs.append(sample_surface(surf))
            ex.Next()
        if not recs:
            ex = TopExp_Explorer(back, TopAbs_EDGE)
            while ex.More():
                c = BRep_Tool.Curve_s(TopoDS.Edge(ex.Current()), 0.0, 1.0)
                recs.append(sample_curve(c))
                ex.Next()
        report[name + ext] = recs
with open(f"{out}/occ_points.json", "w") as f:
    json.dump(report, f, separators=(",", ":"))

"""Writes the STEP and IGES test files of crates/vclay-io/tests/data/cad with OpenCASCADE
(the PyPI package cadquery-ocp), and OpenCASCADE's own evaluation of what it reads back from
them at seeded random parameters (occ_points.json), for crates/vclay-io/tests/cad_read.rs.

B-rep solids with elementary surfaces (box, cylinder, cone, sphere, torus, a revolved B-spline
profile, an extruded B-spline) are written as STEP as OpenCASCADE makes them (not converted to
NURBS); occ_brep_points.json holds, per file and face, the surface type, points of the surface
at random parameters in the face's parameter box, and per edge points of the 3D curve and of
the pcurve on the face at random edge parameters. Parameters are the STEP (ISO 10303-42) ones:
OpenCASCADE's cone parameter v runs along the generatrix and is converted to the height along
the axis (v cos a) here.

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
from OCP.BRepPrimAPI import (BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCone,
                             BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakePrism,
                             BRepPrimAPI_MakeRevol, BRepPrimAPI_MakeSphere,
                             BRepPrimAPI_MakeTorus)
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import GeomAbs_Cone
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface
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
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Pnt, gp_Vec

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


# --- B-rep solids with elementary and swept surfaces (issue 20, STEP only) -------------------

def profile():
    """A B-spline profile in the xz-plane, away from the z axis, for revolution."""
    pts = col.Array1_gp_Pnt(1, 5)
    for i, (x, z) in enumerate([(1.0, 0.0), (1.6, 0.4), (1.2, 1.0), (1.8, 1.6), (1.1, 2.0)]):
        pts.SetValue(i + 1, gp_Pnt(x, 0.0, z))
    return Geom_BSplineCurve(pts, arr1([0.0, 0.5, 1.0]), arr1([4, 1, 4], col.Array1_int), 3)


def extrusion_curve():
    pts = col.Array1_gp_Pnt(1, 4)
    for i, (x, y) in enumerate([(0.0, 0.0), (1.0, 1.0), (2.0, -1.0), (3.0, 0.5)]):
        pts.SetValue(i + 1, gp_Pnt(x, y, 0.0))
    return Geom_BSplineCurve(pts, arr1([0.0, 1.0]), arr1([4, 4], col.Array1_int), 3)


frame = gp_Ax2(gp_Pnt(0.5, -0.25, 0.75), gp_Dir(0.3, -0.2, 1.0), gp_Dir(1.0, 0.0, -0.3))
breps = {
    "brep_box": BRepPrimAPI_MakeBox(gp_Pnt(-1.0, -0.5, 0.25), 2.0, 1.5, 0.75).Shape(),
    "brep_cylinder": BRepPrimAPI_MakeCylinder(frame, 0.8, 1.7).Shape(),
    "brep_cone": BRepPrimAPI_MakeCone(1.0, 0.4, 1.5).Shape(),
    "brep_sphere": BRepPrimAPI_MakeSphere(gp_Pnt(0.2, 0.1, -0.3), 1.3).Shape(),
    "brep_torus": BRepPrimAPI_MakeTorus(frame, 2.0, 0.6).Shape(),
    "brep_revolution": BRepPrimAPI_MakeRevol(
        BRepBuilderAPI_MakeEdge(profile()).Edge(),
        gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1))).Shape(),
    "brep_extrusion": BRepPrimAPI_MakePrism(
        BRepBuilderAPI_MakeEdge(extrusion_curve()).Edge(), gp_Vec(0.2, 0.3, 1.5)).Shape(),
}


def iso_v(adaptor):
    """OpenCASCADE's v to the STEP v (cones: height along the axis)."""
    if adaptor.GetType() == GeomAbs_Cone:
        import math
        c = math.cos(adaptor.Cone().SemiAngle())
        return lambda v: v * c
    return lambda v: v


brep_report = {}
for name, shape in breps.items():
    path = f"{out}/{name}.step"
    write_step(shape, path)
    back = read(path)
    faces = []
    ex = TopExp_Explorer(back, TopAbs_FACE)
    while ex.More():
        face = TopoDS.Face(ex.Current())
        ad = BRepAdaptor_Surface(face, False)
        conv = iso_v(ad)
        surf = BRep_Tool.Surface_s(face)
        u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
        params, points = [], []
        for _ in range(6):
            u, v = rng.uniform(u0, u1), rng.uniform(v0, v1)
            p = surf.Value(u, v)
            params.append([u, conv(v)])
            points.append([p.X(), p.Y(), p.Z()])
        edges = []
        ee = TopExp_Explorer(face, TopAbs_EDGE)
        while ee.More():
            edge = TopoDS.Edge(ee.Current())
            if BRep_Tool.Degenerated_s(edge):
                ee.Next()
                continue
            c3 = BRepAdaptor_Curve(edge)
            c2 = BRepAdaptor_Curve2d(edge, face)
            a, b = c3.FirstParameter(), c3.LastParameter()
            ts, p3, uv = [], [], []
            for _ in range(4):
                t = rng.uniform(a, b)
                p = c3.Value(t)
                q = c2.Value(t)
                ts.append(t)
                p3.append([p.X(), p.Y(), p.Z()])
                uv.append([q.X(), conv(q.Y())])
            edges.append({"params": ts, "points": p3, "uv": uv})
            ee.Next()
        faces.append({"surface": type(surf).__name__, "params": params, "points": points,
                      "edges": edges})
        ex.Next()
    brep_report[name + ".step"] = faces
with open(f"{out}/occ_brep_points.json", "w") as f:
    json.dump(brep_report, f, separators=(",", ":"))

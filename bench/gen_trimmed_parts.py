"""Writes CAD parts made of trimmed faces with OpenCASCADE (cadquery-ocp), for issue 30:

- plate.step: a 40 x 30 x 8 box with a through hole of radius 6 and its four top edges filleted
  with radius 2 (11 faces: planes with a hole, a cylinder, four fillet cylinders);
- cut_sphere.step: a sphere of radius 10 cut by the plane z = 4 (2 faces: the spherical cap
  face with its seam and pole, and a disc on the plane);
- the same parts as IGES in both of OpenCASCADE's forms: NAME_faces.igs (trimmed surfaces 144
  with 142 boundaries, no topology) and NAME_brep.igs (a manifold solid B-rep 186 over the
  analytic surfaces 190-196, with 502-514 topology),

and prints, per part, OpenCASCADE's face count, volume and area (GProp), which
bench/check_trimmed.py compares with what comes back from vclay.

Usage: python gen_trimmed_parts.py OUT_DIR
"""
import json
import sys

from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepGProp import BRepGProp
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakeSphere
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.IGESControl import IGESControl_Writer
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
from OCP.BRep import BRep_Tool
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
from OCP.BRepAdaptor import BRepAdaptor_Curve


def plate():
    box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 40.0, 30.0, 8.0).Shape()
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(20, 15, -1), gp_Dir(0, 0, 1)), 6.0, 10.0).Shape()
    cut = BRepAlgoAPI_Cut(box, hole).Shape()
    f = BRepFilletAPI_MakeFillet(cut)
    ex = TopExp_Explorer(cut, TopAbs_EDGE)
    while ex.More():
        e = TopoDS.Edge(ex.Current())
        c = BRepAdaptor_Curve(e)
        a, b = c.Value(c.FirstParameter()), c.Value(c.LastParameter())
        # Top straight edges: both ends at z = 8 on the box outline.
        if abs(a.Z() - 8) < 1e-9 and abs(b.Z() - 8) < 1e-9 and c.GetType() == 0:
            f.Add(2.0, e)
        ex.Next()
    return f.Shape()


def cut_sphere():
    s = BRepPrimAPI_MakeSphere(10.0).Shape()
    box = BRepPrimAPI_MakeBox(gp_Pnt(-20, -20, 4), 40.0, 40.0, 20.0).Shape()
    return BRepAlgoAPI_Cut(s, box).Shape()


def props(shape):
    n = 0
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        n += 1
        ex.Next()
    v, a = GProp_GProps(), GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, v)
    BRepGProp.SurfaceProperties_s(shape, a)
    return {"faces": n, "volume": v.Mass(), "area": a.Mass()}


out = sys.argv[1]
summary = {}
for name, shape in [("plate", plate()), ("cut_sphere", cut_sphere())]:
    w = STEPControl_Writer()
    w.Transfer(shape, STEPControl_AsIs)
    assert w.Write(f"{out}/{name}.step") == IFSelect_RetDone
    for mode, form in ((0, "faces"), (1, "brep")):
        Interface_Static.SetIVal_s("write.iges.brep.mode", mode)
        wi = IGESControl_Writer("MM", mode)
        wi.AddShape(shape)
        wi.ComputeModel()
        assert wi.Write(f"{out}/{name}_{form}.igs")
    summary[name] = props(shape)
print(json.dumps(summary, indent=1))

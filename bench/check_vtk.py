"""Reads vclay's lattice and frame files with VTK and checks what a ParaView user relies on.

Usage: check_vtk.py VCLAY WORKDIR (see check_vtk.sh).

1. `vclay subdivide --primitive P --levels L --out x.vtu` for every primitive at levels 0 and 1
   (control lattices hold hexahedra, wedges, a tetrahedral frame written as a polyhedron):
   VTK's XML reader takes the file; every cell has positive volume by vtkCellSizeFilter
   (VTK's own orientation conventions); the same lattice's boundary surface written as OBJ is
   closed, consistently oriented outward and encloses the cells' total volume.
2. `vclay run` of a short scenario on a pulled 4^3 cube with frames in every format: each VTU
   frame has positive cell volumes and its point data (points minus `displacement` is the
   first frame's shape; `mass` adds up to the cube's); the OBJ, PLY and STL frames read by
   vtkOBJReader, vtkPLYReader and vtkSTLReader are the same closed surface, enclosing the
   VTU's volume.

3. The closed surfaces of `vclay demo` (the NURBS torus, the twisted volume's boundary, the
   FFD bottles, subdivided lattices' boundaries) are closed and oriented outward.

Prints every failure with the file it concerns and exits non-zero if there was any.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

PRIMITIVES = [
    "box",
    "cylinder",
    "cylinder:6x1x2",
    "torus",
    "paper-torus",
    "gear",
    "cube-with-holes",
    "tetrahedron-with-holes",
    "tetrahedron-with-holes-paper",
    "soccer-player",
    "cactus",
    "spiked-object",
    "holed-object",
    "l",
    "t",
]

# Primitives whose control lattice already has non-planar faces.
WARPED_AT_LEVEL_0 = {"soccer-player"}

SCENARIO = """
[model]
kind = "subdivision-solid"
primitive = "box"
points = [4, 4, 4]
level = 2

[simulation]
dt = 0.002
steps = 60

[[timeline]]
action = "rope"
at = 0.0
from = [1.0, 1.0, 1.0]
to = [1.4, 1.3, 1.2]
until = 0.1

[output]
frames = ["vtu", "obj", "ply", "stl"]
every = 30
"""

# A single non-convex cell of genus 3: MacCracken-Joy puts the new cell point at the centroid
# of its 16 points, inside the central hole, so from level 1 on the interior folds through the
# holes (about half the cells have negative volume; the boundary surface is unaffected). This is
# the rules' behaviour on this control lattice, the paper's model (same counts), not a writer's
# error; the check reports the folded cells and still checks the surface.
# The default `tetrahedron-with-holes` is the same solid split into 6 prisms and 4 tetrahedra
# (issue 19), which does not fold.
FOLDED = {"tetrahedron-with-holes-paper"}

failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL", msg)


def read_vtu(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(str(path))
    r.Update()
    if r.GetErrorCode() != 0:
        fail(f"{path}: VTK reader error {r.GetErrorCode()}")
    return r.GetOutput()


def cell_volumes(grid):
    """Cell volumes: vtkCellSizeFilter for the linear types (VTK's orientation conventions);
    for polyhedra (type 42), whose volume VTK takes from their points as if they were convex
    (the tetrahedral frame of genus 3 gets its convex hull's volume), the divergence theorem
    over the faces as VTK's polyhedron cell returns them (so their orientation is VTK's)."""
    f = vtk.vtkCellSizeFilter()
    f.SetInputData(grid)
    f.ComputeVolumeOn()
    f.Update()
    vols = vtk_to_numpy(f.GetOutput().GetCellData().GetArray("Volume")).copy()
    pts = vtk_to_numpy(grid.GetPoints().GetData())
    for i in range(grid.GetNumberOfCells()):
        if grid.GetCellType(i) != vtk.VTK_POLYHEDRON:
            continue
        cell = grid.GetCell(i)
        v = 0.0
        for k in range(cell.GetNumberOfFaces()):
            face = cell.GetFace(k)
            ids = [face.GetPointId(j) for j in range(face.GetNumberOfPoints())]
            for j in range(1, len(ids) - 1):
                a, b, c = pts[ids[0]], pts[ids[j]], pts[ids[j + 1]]
                v += np.dot(a, np.cross(b, c)) / 6.0
        vols[i] = v
    return vols


def read_surface(path):
    ext = path.suffix.lower()
    r = {".obj": vtk.vtkOBJReader, ".ply": vtk.vtkPLYReader, ".stl": vtk.vtkSTLReader}[ext]()
    r.SetFileName(str(path))
    r.Update()
    clean = vtk.vtkCleanPolyData()  # merge the per-triangle points of STL
    clean.SetInputData(r.GetOutput())
    clean.Update()
    return clean.GetOutput()


def surface_checks(path, poly, want_volume, cells_label, rel=1e-9):
    """Closed, manifold, oriented outward, enclosing `want_volume`; returns (triangles, volume)."""
    tris = poly.GetNumberOfCells()
    if tris == 0:
        fail(f"{path}: no triangles")
        return 0, 0.0
    edges = vtk.vtkFeatureEdges()
    edges.SetInputData(poly)
    edges.BoundaryEdgesOn()
    edges.NonManifoldEdgesOn()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    open_edges = edges.GetOutput().GetNumberOfCells()
    if open_edges:
        fail(f"{path}: {open_edges} boundary or non-manifold edges; the surface is not closed")
    # Orientation: every directed edge appears once and its reverse once.
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    directed = set()
    signed = 0.0
    for c in range(tris):
        ids = poly.GetCell(c).GetPointIds()
        tri = [ids.GetId(k) for k in range(ids.GetNumberOfIds())]
        if len(tri) != 3:
            fail(f"{path}: cell {c} has {len(tri)} points, not 3")
            continue
        for k in range(3):
            e = (tri[k], tri[(k + 1) % 3])
            if e in directed:
                fail(f"{path}: edge {e} used twice in the same direction (inconsistent orientation)")
                break
            directed.add(e)
        a, b, c3 = pts[tri[0]], pts[tri[1]], pts[tri[2]]
        signed += np.dot(a, np.cross(b, c3)) / 6.0
    if signed <= 0:
        fail(f"{path}: enclosed volume {signed:.6g} is not positive (normals point inward)")
    if want_volume is not None and abs(signed - want_volume) > rel * abs(want_volume):
        fail(f"{path}: encloses {signed:.6g}, the {cells_label} total {want_volume:.6g}")
    return tris, signed


def check_lattices(vclay, work):
    n = 0
    for prim in PRIMITIVES:
        for level in (0, 1, 2):
            stem = work / f"{prim.replace(':', '_')}_l{level}"
            for ext in ("vtu", "obj"):
                subprocess.run(
                    [vclay, "subdivide", "--primitive", prim, "--levels", str(level),
                     "--out", f"{stem}.{ext}"],
                    check=True, capture_output=True,
                )
            grid = read_vtu(f"{stem}.vtu")
            vols = cell_volumes(grid)
            types = sorted({grid.GetCellType(i) for i in range(grid.GetNumberOfCells())})
            if prim in FOLDED and level > 0:
                folded = int((vols <= 0).sum())
                tris, vol = surface_checks(Path(f"{stem}.obj"), read_surface(Path(f"{stem}.obj")),
                                           None, "")
                print(f"ok {stem.name}: {grid.GetNumberOfCells()} cells, {folded} folded "
                      f"(negative volume, expected for this model); surface {tris} triangles, "
                      f"closed and outward, encloses {vol:.6g}")
                n += 1
                continue
            if len(vols) == 0 or vols.min() <= 0:
                bad = int(np.argmin(vols)) if len(vols) else -1
                fail(f"{stem}.vtu: cell {bad} has volume {vols.min() if len(vols) else 'n/a'} "
                     f"(VTK cell type {grid.GetCellType(bad) if bad >= 0 else '-'})")
                continue
            # The primitives' faces are planar at level 0, so the surface encloses exactly
            # the cells' volume; at level 1 faces warp, and VTK's hexahedron volume (its own
            # split into tetrahedra) and the surface's split of each quad into two triangles
            # agree only to about the warp (under 1 % at levels 1 and 2). The soccer player's
            # limbs are placed turned, so its level-0 faces warp too (0.35 %).
            planar = level == 0 and prim not in WARPED_AT_LEVEL_0
            rel = 1e-9 if planar else 1e-2
            tris, vol = surface_checks(Path(f"{stem}.obj"), read_surface(Path(f"{stem}.obj")),
                                       vols.sum(), "VTU cells'", rel)
            print(f"ok {stem.name}: {grid.GetNumberOfCells()} cells (VTK types {types}), "
                  f"volumes {vols.min():.4g}..{vols.max():.4g}, total {vols.sum():.6g}; "
                  f"surface {tris} triangles, encloses {vol:.6g}")
            n += 1
    return n


def check_frames(vclay, work):
    scen = work / "frames.toml"
    scen.write_text(SCENARIO)
    out = work / "frames"
    subprocess.run([vclay, "run", str(scen), "--out", str(out)], check=True, capture_output=True)
    steps = sorted({p.stem for p in out.glob("frame_*.vtu")})
    if len(steps) < 2:
        fail(f"{out}: {len(steps)} VTU frames written")
    rest = None
    for stem in steps:
        grid = read_vtu(out / f"{stem}.vtu")
        vols = cell_volumes(grid)
        if vols.min() <= 0:
            fail(f"{stem}.vtu: a cell has volume {vols.min()}")
        # Point data as VTK reads it: points minus displacement is the rest shape, the same in
        # every frame (the first frame's points); masses add up to the cube's (density 1).
        pd = grid.GetPointData()
        arrays = {pd.GetArrayName(i): pd.GetArray(i) for i in range(pd.GetNumberOfArrays())}
        want = {"displacement": 3, "velocity": 3, "spring_force": 3, "mass": 1}
        for name, comps in want.items():
            a = arrays.get(name)
            if a is None or a.GetNumberOfComponents() != comps \
                    or a.GetNumberOfTuples() != grid.GetNumberOfPoints():
                fail(f"{stem}.vtu: point data {name} missing or mis-shaped")
                return len(steps)
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        this_rest = pts - vtk_to_numpy(arrays["displacement"])
        if rest is None:
            rest = pts.copy()
        if np.abs(this_rest - rest).max() > 1e-9:
            fail(f"{stem}.vtu: points - displacement is not the rest shape "
                 f"(off by {np.abs(this_rest - rest).max():.3g})")
        mass = vtk_to_numpy(arrays["mass"]).sum()
        if abs(mass - 1.0) > 1e-9:
            fail(f"{stem}.vtu: masses add up to {mass}, not the unit cube's 1")
        counts = []
        for ext in ("obj", "ply", "stl"):
            path = out / f"{stem}.{ext}"
            tris, vol = surface_checks(path, read_surface(path), vols.sum(), "VTU cells'", 1e-2)
            counts.append((ext, tris, vol))
        # VTK's PLY and STL readers keep points in single precision.
        same = len({c[1] for c in counts}) == 1 and \
            max(abs(c[2] - counts[0][2]) for c in counts) <= 1e-5 * abs(counts[0][2])
        if not same:
            fail(f"{stem}: the surface formats disagree: {counts}")
        print(f"ok {stem}: {grid.GetNumberOfCells()} hexahedra, total volume {vols.sum():.6g}; "
              + ", ".join(f"{e} {t} triangles encl. {v:.6g}" for e, t, v in counts))
    return len(steps)


# Closed surfaces that `vclay demo` writes: each must be closed and oriented outward.
DEMO_CLOSED = [
    "torus.obj",
    "twisted_volume.obj",
    "ffd/fig3a-bottle.obj",
    "ffd/fig3b-bottle.obj",
    "subdivision/gear-level2.obj",
    "subdivision/tetrahedron-with-holes-level3.obj",
    "subdivision/soccer-player-level2.obj",
    "subdivision/cactus-level2.obj",
    "subdivision/spiked-object-level1.obj",
    "subdivision/holed-object-level1.obj",
]


def check_demo(vclay, work):
    out = work / "demo"
    subprocess.run([vclay, "demo", "--out", str(out)], check=True, capture_output=True)
    for name in DEMO_CLOSED:
        path = out / name
        if not path.exists():
            fail(f"{path}: not written by vclay demo")
            continue
        tris, vol = surface_checks(path, read_surface(path), None, "")
        print(f"ok demo/{name}: {tris} triangles, closed and outward, encloses {vol:.6g}")
    return len(DEMO_CLOSED)


def main():
    vclay, work = sys.argv[1], Path(sys.argv[2])
    print(f"check_vtk: VTK {vtk.vtkVersion.GetVTKVersion()}")
    lattices = check_lattices(vclay, work)
    frames = check_frames(vclay, work)
    demo = check_demo(vclay, work)
    if failures:
        print(f"check_vtk: FAILED ({len(failures)} problems)")
        sys.exit(1)
    print(f"check_vtk: passed: {lattices} lattices, {frames} scenario frames, "
          f"{demo} closed demo surfaces")


if __name__ == "__main__":
    main()

"""FFD direct manipulation hits its targets; subdivision lattices; PDE surfaces from a dict."""

import json

import numpy as np

import vclay


def test_single_point_move_hits_its_target(rng):
    f = vclay.Ffd([0, 0, 0], [2, 1, 1], degree=3, control_points=5)
    pts = rng.uniform([0, 0, 0], [2, 1, 1], (1000, 3))
    np.testing.assert_allclose(f.deform(pts), pts, atol=1e-12)  # identity at rest
    src, dst = np.array([1.0, 0.5, 0.5]), np.array([1.2, 0.7, 0.4])
    f.move_point(src, dst)
    np.testing.assert_allclose(f.deform(src[None]), dst[None], atol=1e-12)
    moved = f.deform(pts)
    assert np.abs(moved - pts).max() > 1e-3


def test_multi_point_move_hits_every_target(rng):
    f = vclay.Ffd.enclosing(rng.uniform(-1, 1, (50, 3)), control_points=[6, 6, 6])
    src = np.array([[0.0, 0.0, 0.0], [0.5, -0.5, 0.2], [-0.6, 0.4, -0.3]])
    dst = src + np.array([[0.1, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, -0.1]])
    f.move_points(src, dst)
    np.testing.assert_allclose(f.deform(src), dst, atol=1e-10)
    assert f.control_points.shape == (6, 6, 6, 3)
    vol = f.volume()
    np.testing.assert_allclose(vol.evaluate(f.parameters(src)), dst, atol=1e-10)
    f.reset()
    np.testing.assert_allclose(f.deform(src), src, atol=1e-12)


def test_lattice_primitives_subdivide_and_ovm(tmp_path):
    box = vclay.Lattice.primitive("box:3x3x3")
    st = box.stats()
    assert (st["points"], st["cells"]) == (27, 8)
    fine = box.subdivide(2, boundary="sharp")
    assert fine.stats()["cells"] == 8 * 64
    assert fine.stats()["inverted_cells"] == 0
    p = tmp_path / "fine.ovm"
    fine.write(p)
    back = vclay.Lattice.read(p)
    np.testing.assert_allclose(back.points, fine.points, atol=1e-12)
    v, t, n = fine.boundary()
    assert len(t) > 0
    moved = box.with_points(box.points * 2.0)
    np.testing.assert_allclose(moved.points, box.points * 2.0)


def test_pde_surface_from_a_dict(root):
    spec = json.loads((root / "crates/vclay-pde/examples/specs/section3.json").read_text())
    s = vclay.PdeSurface(spec)
    assert s.patches == ["surface"]
    v, t, n = s.mesh(grid=(16, 12))
    assert v.shape == (16 * 12, 3)
    uv = np.array([[0.0, 1.0], [1.0, 2.0]])
    pts = s.evaluate(uv)
    # u = 1 is the boundary curve (r sin v, -r cos v, 0) with r = 1.
    np.testing.assert_allclose(pts[1], [np.sin(2.0), -np.cos(2.0), 0.0], atol=1e-9)
    assert s.residual() >= 0.0


def test_pde_residual_check_warns_on_fig6a_at_t1(root):
    # Issue 28: fig6a at t = 1 is a disc on a pinched spindle (residual RMS 0.081, 2.1 % of
    # the surface's size); at t = 0.5 the PDE is solved to rounding.
    spec = json.loads((root / "examples/pde/fig6a.json").read_text())
    s = vclay.PdeSurface(spec)
    bad, good = s.residual_check(1.0), s.residual_check(0.5)
    assert bad["ratio"] > 0.01 and "residual RMS" in bad["warning"]
    assert abs(bad["ratio"] - bad["residual_rms"] / bad["size"]) < 1e-15
    assert good["ratio"] < 1e-10 and good["warning"] is None

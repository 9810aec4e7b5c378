"""Geometry can be written back (issue 32 item 5): writable `control_points`/`weights` with
validation on entities and FFD lattices; sessions give control points in the net's shape (as
`Entity.control_points`), weights, the current `Surface`, and take new control points and
weights as one undoable edit; `vclay.clay` makes a solid from a mesh."""

import numpy as np
import pytest

import vclay
from test_dnurbs import flat_sheet


def test_entity_control_points_and_weights_are_writable():
    k = [0, 0, 0, 1, 1, 1]
    s = vclay.Surface((2, 2), (k, k), flat_sheet(3))
    cp = s.control_points
    cp[1, 1, 2] = 1.0
    s.control_points = cp
    assert s.point(0.5, 0.5)[2] == pytest.approx(0.25)
    w = np.ones((3, 3))
    w[1, 1] = 3.0
    s.weights = w
    np.testing.assert_array_equal(s.weights, w)
    assert s.point(0.5, 0.5)[2] == pytest.approx(0.5)
    with pytest.raises(ValueError, match=r"control_points: expected shape \[3, 3, 3\]"):
        s.control_points = np.zeros((9, 3))
    with pytest.raises(ValueError, match="not finite"):
        s.control_points = np.full((3, 3, 3), np.nan)
    with pytest.raises(ValueError, match="weights: value 4 .* not positive"):
        s.weights = np.where(w == 3.0, -1.0, 1.0)
    np.testing.assert_array_equal(s.weights, w)  # unchanged by the refused writes


def test_ffd_control_points_and_weights_are_writable():
    f = vclay.Ffd([0, 0, 0], [1, 1, 1], degree=2, control_points=3)
    cp = f.control_points
    cp[1, 1, 1] += [0.0, 0.0, 0.5]
    f.control_points = cp
    assert f.deform([[0.5, 0.5, 0.5]])[0, 2] > 0.55  # 0.5 + 0.5 N_1(0.5)^3
    assert f.weights.shape == (3, 3, 3)
    with pytest.raises(ValueError, match="control_points: expected shape"):
        f.control_points = cp[:2]
    with pytest.raises(vclay.GeometryError):
        f.weights = np.zeros((3, 3, 3))


def test_session_geometry_round_trip():
    s = vclay.dnurbs_surface(flat_sheet(5), degree=(2, 2), dt=0.01, dynamic_weights=True)
    cp = s.control_points()
    assert cp.shape == (5, 5, 3)
    assert s.weights().shape == (5, 5)
    surf = s.surface()
    assert isinstance(surf, vclay.Surface)
    np.testing.assert_array_equal(surf.control_points, cp)
    cp[2, 2, 2] = 0.4
    assert s.set_control_points(cp) == 1
    np.testing.assert_array_equal(s.control_points(), cp)
    assert s.surface().point(0.5, 0.5)[2] > 0.0
    w = s.weights()
    w[2, 2] = 2.0
    assert s.set_weights(w) == 1
    assert s.weights()[2, 2] == 2.0
    s.undo()
    assert s.weights()[2, 2] == 1.0
    s.undo()
    assert s.control_points()[2, 2, 2] == 0.0
    with pytest.raises(ValueError, match="expected 25 points"):
        s.set_control_points(np.zeros((4, 3)))
    solid = vclay.open(__import__("pathlib").Path(__file__).resolve().parents[2]
                       / "examples/scenarios/fig07_rope_cube.toml")
    assert solid.control_points().ndim == 2  # a subdivision lattice is not a grid
    assert solid.entities() == []
    with pytest.raises(vclay.SessionError, match="no NURBS surface"):
        solid.surface()


def test_clay_from_arrays():
    # An octahedron: a closed mesh.
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    t = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                  [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    s = vclay.clay((v, t), cells=8, level=1)
    assert s.kind() == "subdivision-solid" and s.models == ["clay"]
    s.step(2)
    assert np.isfinite(s.data_points()).all()
    with pytest.raises(ValueError, match="cells = -1"):
        vclay.clay((v, t), cells=-1)

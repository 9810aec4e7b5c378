"""Commands take numpy arrays and scalars (issue 32 item 2): a dict is converted in Rust into
the session layer's typed `Command` (no `json.dumps`, no JSON text); a NaN or a value of a
wrong type is a `CommandError` naming its key."""

import numpy as np
import pytest

import vclay
from test_dnurbs import flat_sheet, paraboloid_points


def sheet():
    return vclay.dnurbs_surface(flat_sheet(), degree=(3, 3),
                                material={"preset": "Hemisphere fitting"})


def test_ndarray_points_equal_list_points():
    pts = paraboloid_points()
    a, b = sheet(), sheet()
    a.apply({"action": "data", "points": pts})
    b.apply({"action": "data", "points": pts.tolist()})
    a.step(5)
    b.step(5)
    np.testing.assert_array_equal(a.control_points(), b.control_points())
    assert a.log[0]["command"] == b.log[0]["command"]
    # float32 arrays and a Fortran-ordered view read the same values.
    c = sheet()
    c.apply({"action": "data", "points": np.asfortranarray(pts.astype(np.float32))})
    got = np.array(c.log[0]["command"]["points"])
    np.testing.assert_array_equal(got, pts.astype(np.float32).astype(np.float64))


def test_numpy_scalars(root):
    s = vclay.Session.load(root / "examples/scenarios/fig07_rope_cube.toml")
    s.apply({"action": "set", "name": "edge_stiffness", "value": np.float32(80.0)})
    assert {p["name"]: p["value"] for p in s.params()}["edge_stiffness"] == 80.0
    s.apply({"action": "gravity", "g": np.array([0, 0, -1], dtype=np.int64)})
    s.apply({"action": "gravity", "g": [np.int64(0), np.float64(0.5), np.int32(-2)]})
    assert s.log[-1]["command"]["g"] == [0.0, 0.5, -2.0]
    s.schedule([{"at": np.float64(0.01), "action": "gravity", "g": (0, 0, np.float16(-3))}])
    s.step(10)
    assert s.log[-1]["command"]["g"] == [0.0, 0.0, -3.0]


def test_nan_and_bad_values_name_the_key(root):
    s = vclay.Session.load(root / "examples/scenarios/fig07_rope_cube.toml")
    with pytest.raises(vclay.CommandError, match=r"command: g\[2\]: NaN is not a finite number"):
        s.apply({"action": "gravity", "g": [0, 0, float("nan")]})
    pts = paraboloid_points()
    pts[3, 1] = np.inf
    with pytest.raises(vclay.CommandError, match=r"command: points\[3\]\[1\]: inf is not a finite"):
        sheet().apply({"action": "data", "points": pts})
    with pytest.raises(vclay.CommandError, match=r"command: g: a value of type object"):
        s.apply({"action": "gravity", "g": object()})
    with pytest.raises(vclay.CommandError, match=r"command: .*missing field `g`"):
        s.apply({"action": "gravity"})
    with pytest.raises(vclay.CommandError, match=r"command: .*invalid length 2"):
        s.apply({"action": "gravity", "g": np.zeros(2)})
    assert s.log == []

"""vclay errors become VclayError subclasses carrying the kernel's located message."""

import json

import numpy as np
import pytest

import vclay


def test_hierarchy():
    for cls in (vclay.FileError, vclay.GeometryError, vclay.PdeError, vclay.RenderError,
                vclay.SessionError):
        assert issubclass(cls, vclay.VclayError)
    assert issubclass(vclay.CommandError, vclay.SessionError)
    assert issubclass(vclay.DivergedError, vclay.SessionError)


def test_model_file_error_names_the_json_path(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps({"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1],
                             "control_points": [[0, 0, 0], [1, 2, "x"]]}))
    with pytest.raises(vclay.FileError) as e:
        vclay.load(p)
    msg = str(e.value)
    assert "bad.json" in msg and "control_points[1]" in msg


def test_json_syntax_error_names_line_and_column(tmp_path):
    p = tmp_path / "syntax.json"
    p.write_text('{"type": "nurbs-curve",\n  "degree": 1,,\n}')
    with pytest.raises(vclay.FileError, match=r"syntax.json.*line 2"):
        vclay.load(p)


def test_geometry_errors():
    with pytest.raises(vclay.GeometryError, match="knot"):
        vclay.Curve(2, [0, 0, 1, 0.5, 1, 1], np.zeros((3, 3)))
    c = vclay.Curve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 1, 1]])
    with pytest.raises(vclay.GeometryError, match=r"params\[1\]"):
        c.evaluate([0.5, 2.0])
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        vclay.Curve(1, [0, 0, 1, 1], np.zeros((2, 2)))


def test_ffd_source_outside_the_box():
    f = vclay.Ffd([0, 0, 0], [1, 1, 1])
    with pytest.raises(vclay.GeometryError, match="outside"):
        f.move_point([2, 2, 2], [0, 0, 0])


def test_scenario_error_names_file_line_and_key(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text('[model]\nkind = "subdivision-solid"\nprimitive = "box"\n\n'
                 '[simulation]\ndt = -1.0\n')
    with pytest.raises(vclay.FileError) as e:
        vclay.Session.load(p)
    msg = str(e.value)
    assert "bad.toml:6" in msg and "dt" in msg


def test_command_error_leaves_the_session_unchanged(root):
    s = vclay.Session.load(root / "examples/scenarios/fig07_rope_cube.toml")
    before = s.data_points()
    with pytest.raises(vclay.CommandError, match="command `set` on model"):
        s.apply({"action": "set", "name": "no_such_parameter", "value": 1.0})
    with pytest.raises(vclay.CommandError):
        s.apply({"action": "no-such-action"})
    np.testing.assert_array_equal(s.data_points(), before)
    with pytest.raises(vclay.SessionError, match="nothing to redo"):
        s.redo()


def test_lattice_file_error_names_the_line(tmp_path):
    p = tmp_path / "bad.ovm"
    p.write_text("OVM ASCII\nVertices\n2\n0 0 0\n1 1\n")
    with pytest.raises(vclay.FileError, match="bad.ovm"):
        vclay.Lattice.read(p)


def test_pde_spec_error():
    with pytest.raises(vclay.PdeError, match="spec"):
        vclay.PdeSurface({"name": "x", "patches": "not a list"})

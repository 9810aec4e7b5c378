"""Session round trip: load a scenario, step, save, load, step equals stepping straight
through (bit for bit); commands, undo and redo."""

import numpy as np

import vclay

SCENARIO = "examples/scenarios/fig07_rope_cube.toml"


def test_round_trip_equals_stepping_straight_through(root, tmp_path):
    straight = vclay.Session.load(root / SCENARIO)
    straight.step(20)
    a = vclay.Session.load(root / SCENARIO)
    a.step(10)
    path = tmp_path / "mid.json"
    a.save(path)
    b = vclay.Session.load(path)
    assert b.steps() == 10
    b.step(10)
    assert b.steps() == straight.steps() == 20
    np.testing.assert_array_equal(b.data_points(), straight.data_points())
    np.testing.assert_array_equal(b.control_points(), straight.control_points())
    assert b.time == straight.time


def test_commands_undo_redo(root):
    s = vclay.Session.load(root / SCENARIO)
    assert s.kind() == "subdivision-solid"
    assert s.data_points().shape == (13 ** 3, 3)
    names = [p["name"] for p in s.params()]
    assert "edge_stiffness" in names
    msg = s.apply({"action": "set", "name": "edge_stiffness", "value": 80.0})
    assert isinstance(msg, str)
    value = {p["name"]: p["value"] for p in s.params()}["edge_stiffness"]
    assert value == 80.0
    entry = s.undo()
    assert entry["command"]["action"] == "set"
    assert {p["name"]: p["value"] for p in s.params()}["edge_stiffness"] == 100.0
    s.redo()
    assert {p["name"]: p["value"] for p in s.params()}["edge_stiffness"] == 80.0
    s.apply('{"action": "gravity", "g": [0, 0, -1]}')
    assert [e["command"]["action"] for e in s.log] == ["set", "gravity"]
    s.step(3)
    assert s.energy()["total"] > 0.0
    v, t, n = s.mesh()
    assert len(t) > 0


def test_run_writes_the_scenario_outputs(root, tmp_path):
    s = vclay.Session.load(root / "examples/scenarios/bspline_rope.toml")
    assert s.scenario_steps == 100
    out = s.run(tmp_path / "run", steps=5)
    assert out["steps"] == 5
    assert any(str(f).endswith("energy.csv") for f in out["files"])
    assert s.control_points().shape == (4, 4, 4, 3)  # a B-spline solid's net


def test_open_recognizes_every_file_kind(root, tmp_path):
    """`vclay.open` is the one way in (issue 26): the same as the studio's Open and `vclay run`."""
    assert vclay.open(root / SCENARIO).kind() == "subdivision-solid"
    assert vclay.open(root / "examples/pde/fig5b.json").kind() == "pde-surface"
    tri = vclay.open(root / "examples/triangular/saddle_patch.json")
    assert tri.kind() == "dnurbs-triangular"
    assert tri.scenario_steps is None
    cloud = tmp_path / "scan.xyz"
    cloud.write_text("0 0 0\n1 0 0\n0 1 1\n")
    try:
        vclay.open(cloud)
        raise AssertionError("a point cloud is not a session")
    except vclay.FileError as e:
        assert "vclay fit" in str(e)


def test_tools_say_what_a_model_takes(root):
    s = vclay.open(root / SCENARIO)
    tools = {t["action"]: t for t in s.tools()}
    assert "extrude" in tools and "pde-set" not in tools
    rope = {k["name"]: k for k in tools["rope"]["keys"]}
    assert rope["from"]["required"] and rope["from"]["unit"] == "length"
    assert "param" not in rope  # a solid's rope has no material point
    assert tools["material"]["acts_on"] == "cell"
    try:
        s.apply({"action": "pde-set", "name": "t", "value": 1.0})
        raise AssertionError("a solid does not take pde-set")
    except vclay.CommandError as e:
        assert "does not take `pde-set`" in str(e)

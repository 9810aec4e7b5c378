"""Issue 30: a STEP part of trimmed faces opens with `vclay.open` as a `cad-part` whose
largest face is a D-NURBS surface; a rope pulls it, the part exports back as STEP and as the
model JSON (which opens again as a part), and a pickled session continues bit for bit."""

import pickle

import numpy as np

import vclay

PLATE = "crates/vclay-io/tests/data/cad/trimmed_plate.step"


def test_a_step_part_opens_sculpts_and_exports(root, tmp_path):
    s = vclay.open(root / PLATE)
    assert s.kind() == "cad-part"
    tools = {t["action"] for t in s.tools()}
    assert {"rope", "force", "fix", "free"} <= tools and "inflate" not in tools
    before = s.control_points().copy()
    s.apply({"action": "rope", "name": "pull", "from": [8.0, 15.0, 0.0],
             "velocity": [0.0, 0.0, -20.0], "stiffness": 200.0})
    s.step(10)
    after = s.control_points()
    assert after.shape == before.shape
    assert np.abs(after - before).max() > 1e-3, "the face moved"
    step, model = tmp_path / "part.step", tmp_path / "part.json"
    s.export(step)
    s.export(model)
    assert step.read_text().count("MANIFOLD_SOLID_BREP") == 1
    assert vclay.open(model).kind() == "cad-part"
    # Pickling is the session file: the copy continues exactly as the original.
    copy = pickle.loads(pickle.dumps(s))
    s.step(3)
    copy.step(3)
    np.testing.assert_array_equal(copy.control_points(), s.control_points())

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


def test_load_part_reads_the_trims_and_writes_them_back(root, tmp_path):
    """Issue 30, "the Python module carries them": the plate's 11 trimmed faces, their loops
    (the top face has a hole), a crack-free mesh with the face of each triangle whose volume is
    the plate's, and STEP/IGES/JSON written back that read again as the same closed part."""
    part = vclay.load_part(root / PLATE)
    assert part.shell_count() == 1 and part.closed(0)
    faces = part.faces(0)
    assert len(faces) == 11
    holed = [f for f in faces if len(f["loops"]) == 2]
    assert len(holed) == 2, "the top and the bottom have the hole"
    for f in faces:
        assert f["entity"] is not None and isinstance(f["surface"], vclay.Surface)
        for poly in f["loops"]:
            assert poly.ndim == 2 and poly.shape[1] == 2 and len(poly) >= 3
    # Every edge is used twice, once each way (a closed shell).
    uses = {}
    for f in faces:
        for loop in f["edges"]:
            for e, fwd in loop:
                if e >= 0:
                    uses.setdefault(e, []).append(fwd)
    assert len(uses) == len(part.edges(0))
    assert all(sorted(v) == [False, True] for v in uses.values())
    v, t, n, face_of = part.mesh(0, samples=48)
    assert face_of.shape == (len(t),) and set(face_of.tolist()) == set(range(11))
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    plate = 40 * 30 * 8 - np.pi * 36 * 8 - (4 - np.pi) * 140
    assert abs(volume - plate) < 1e-2 * plate, volume
    for ext in ["step", "igs", "json"]:
        out = tmp_path / f"plate.{ext}"
        part.save(out)
        back = vclay.load_part(out)
        assert back.closed(0) and len(back.faces(0)) == 11, ext
        vb, tb, _, _ = back.mesh(0, samples=48)
        a, b, c = vb[tb[:, 0]], vb[tb[:, 1]], vb[tb[:, 2]]
        vol = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
        assert abs(vol - volume) < 1e-3 * plate, (ext, vol, volume)
    # Pickling is exact; entities are the load() list's.
    copy = pickle.loads(pickle.dumps(part))
    assert copy.to_json() == part.to_json()
    assert len(part.entities) == len(vclay.load(root / PLATE))


def test_load_part_refuses_a_file_without_trims(root, tmp_path):
    out = tmp_path / "sheet.json"
    vclay.save(out, vclay.load(root / PLATE)[:1])
    try:
        vclay.load_part(out)
    except vclay.FileError as e:
        assert "no trimmed faces" in str(e) and "load" in str(e)
    else:
        raise AssertionError("a file without shells gave a Part")

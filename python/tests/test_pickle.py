"""Pickle, copy and Dask (issue 32 item 3): every class pickles and copies exactly; a pickled
Session continues bit for bit (the session file's save/load); `Session.from_dict` reads what
`to_dict` gives; `client.submit(f, session)` ships a session to a Dask worker."""

import copy
import pickle
import sys
from pathlib import Path

import numpy as np
import pytest

import vclay

SCENARIO = "examples/scenarios/fig07_rope_cube.toml"


def roundtrip(x):
    return pickle.loads(pickle.dumps(x))


def test_entities(rng):
    ku, kv = [0, 0, 0, 0.3, 1, 1, 1], [0, 0, 0, 1, 1, 1]
    s = vclay.Surface((2, 2), (ku, kv), rng.random((4, 3, 3)), rng.random((4, 3)) + 0.5,
                      name="patch")
    c = vclay.Curve(2, [0, 0, 0, 1, 1, 1], rng.random((3, 3)))
    v = vclay.Volume((1, 1, 1), ([0, 0, 1, 1],) * 3, rng.random((2, 2, 2, 3)))
    for e in (s, c, v):
        for f in (roundtrip(e), copy.copy(e), copy.deepcopy(e)):
            assert type(f) is type(e) and f == e and f.name == e.name
            np.testing.assert_array_equal(f.control_points, e.control_points)
            np.testing.assert_array_equal(f.weights, e.weights)
    assert s != vclay.Surface((2, 2), (ku, kv), s.control_points, s.weights)  # no name


def test_ffd_lattice_pde(root):
    f = vclay.Ffd([0, 0, 0], [1, 2, 3], degree=2, control_points=(3, 4, 5))
    f.move_point([0.5, 0.5, 0.5], [0.7, 0.4, 0.9])
    g = roundtrip(f)
    assert g == f and copy.deepcopy(f) == f
    x = np.random.default_rng(1).random((50, 3))
    np.testing.assert_array_equal(g.deform(x), f.deform(x))
    g.reset()
    assert g != f
    lat = vclay.Lattice.primitive("torus").subdivide(1)
    m = roundtrip(lat)
    assert m == lat and copy.deepcopy(lat) == lat
    np.testing.assert_array_equal(m.points, lat.points)
    p = vclay.PdeSurface.read(root / "examples/pde/fig5b.json")
    q = roundtrip(p)
    uv = np.random.default_rng(2).random((20, 2))
    np.testing.assert_array_equal(q.evaluate(uv, t=0.3), p.evaluate(uv, t=0.3))


def test_pickled_session_continues_bit_for_bit(root):
    straight = vclay.Session.load(root / SCENARIO)
    straight.step(12)
    a = vclay.Session.load(root / SCENARIO)
    a.step(6)
    for b in (roundtrip(a), copy.deepcopy(a), vclay.Session.from_dict(a.to_dict())):
        assert b.steps() == 6 and b.time == a.time
        b.step(6)
        np.testing.assert_array_equal(b.data_points(), straight.data_points())
        np.testing.assert_array_equal(b.control_points(), straight.control_points())
        assert b.energy() == straight.energy()
    # The copy is independent of the original.
    assert a.steps() == 6
    with pytest.raises(vclay.FileError, match="from_dict"):
        vclay.Session.from_dict({"format": "something else"})


def step_session(session, n):
    """A Dask task: steps a session it received and returns it."""
    session.step(n)
    return session


def test_dask_ships_sessions(root):
    pytest.importorskip("dask.distributed")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
    import dask_sweep

    s = vclay.dnurbs_surface(np.stack(np.meshgrid(*[np.linspace(0, 1, 6)] * 2, [0.0],
                                                  indexing="ij"), -1)[:, :, 0, :],
                             degree=(3, 3), dt=0.01)
    s.apply({"action": "gravity", "g": [0, 0, -9.8]})
    client = dask_sweep.local_client(1)
    try:
        remote = client.submit(step_session, s, 15, pure=False).result()
    finally:
        client.close()
        client.cluster.close()
    s.step(15)
    np.testing.assert_array_equal(remote.control_points(), s.control_points())
    assert remote.log == s.log

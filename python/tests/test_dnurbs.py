"""D-NURBS from Python without a scenario file: `dnurbs_surface` from arrays and
`Session.from_toml`; data points fit a sheet to a paraboloid; material changes and steps."""

import numpy as np
import pytest

import vclay


def flat_sheet(n=8):
    x = np.linspace(-1.0, 1.0, n)
    X, Y = np.meshgrid(x, x, indexing="ij")
    return np.stack([X, Y, np.zeros_like(X)], axis=-1)


def paraboloid_points(m=7):
    g = np.linspace(-0.8, 0.8, m)
    X, Y = np.meshgrid(g, g, indexing="ij")
    return np.stack([X.ravel(), Y.ravel(), 0.5 * (X ** 2 + Y ** 2).ravel()], axis=-1)


def rms_to_mesh(session, points, order=6):
    """RMS distance from `points` to the display mesh, sampled at barycentric points of
    every triangle (spacing 1/order of a triangle's edge)."""
    v, t, _ = session.mesh()
    ab = [(i / order, j / order) for i in range(order + 1) for j in range(order + 1 - i)]
    bary = np.array([(a, b, 1.0 - a - b) for a, b in ab])
    samples = np.einsum("kc,tcx->tkx", bary, v[t]).reshape(-1, 3)
    d = np.sqrt(((points[:, None, :] - samples[None, :, :]) ** 2).sum(-1)).min(axis=1)
    return float(np.sqrt((d ** 2).mean()))


def test_fit_a_sheet_to_a_paraboloid():
    s = vclay.dnurbs_surface(flat_sheet(), degree=(3, 3),
                             material={"preset": "Hemisphere fitting"})
    assert s.kind() == "dnurbs-surface"
    cp0 = s.control_points()
    assert cp0.shape == (8, 8, 3)  # the net's shape, as Surface.control_points
    np.testing.assert_array_equal(cp0, flat_sheet())
    pts = paraboloid_points()
    before = rms_to_mesh(s, pts)
    s.apply({"action": "data", "points": pts.tolist()})
    s.step(100)
    after = rms_to_mesh(s, pts)
    assert after < before / 5, (before, after)
    # The net rose towards the paraboloid (z = 0.5 (x^2 + y^2) >= 0 over the data).
    assert s.control_points()[..., 2].mean() > 0.1
    # The data points are a tool of the model, saved with it.
    assert s.state()["tools"]["tools"][0]["action"] == "data"


def test_material_and_step(tmp_path):
    s = vclay.dnurbs_surface(flat_sheet(6), degree=(2, 2), dt=0.01, name="sheet",
                             material={"mu": 1.0, "gamma": 2.0, "alpha": 5.0, "beta": 1.0},
                             dynamic_weights=False)
    assert s.models == ["sheet"]
    params = {p["name"]: p["value"] for p in s.params()}
    assert (params["mu"], params["gamma"], params["alpha"], params["dt"]) == (1.0, 2.0, 5.0, 0.01)
    s.apply({"action": "material", "mu": 3.0, "gamma": 0.5})
    params = {p["name"]: p["value"] for p in s.params()}
    assert (params["mu"], params["gamma"]) == (3.0, 0.5)
    s.apply({"action": "gravity", "g": [0.0, 0.0, -9.8]})
    s.step(20)
    assert s.steps() == 20  # steps of dt (the engine may halve some inside)
    assert s.energy()["kinetic"] > 0.0
    assert s.control_points()[..., 2].mean() < 0.0
    path = tmp_path / "sheet.json"
    s.save(path)
    again = vclay.Session.load(path)
    np.testing.assert_array_equal(again.control_points(), s.control_points())


def test_from_toml_and_its_errors(root, tmp_path):
    text = (root / "examples/scenarios/fig7a_hemisphere_fit.toml").read_text()
    s = vclay.Session.from_toml(text)
    assert s.kind() == "dnurbs-surface" and s.scenario_steps == 300
    s.step(5)
    assert s.steps() == 5
    with pytest.raises(vclay.FileError, match=r"<string>:3: kind: unknown model kind"):
        vclay.Session.from_toml("[model]\n\nkind = 'no-such-kind'\n")
    # Relative model files resolve against `base`.
    vclay.save(tmp_path / "net.json",
               [vclay.Surface((2, 2), ([0, 0, 0, 1, 1, 1],) * 2, flat_sheet(3))])
    s = vclay.Session.from_toml(
        '[model]\nkind = "dnurbs-surface"\nfile = "net.json"\n[simulation]\ndt = 0.01\n',
        base=tmp_path)
    assert s.control_points().shape == (3, 3, 3)
    with pytest.raises(vclay.VclayError):
        vclay.dnurbs_surface(flat_sheet(), material={"mu": -1.0}, dt=0.01)
    with pytest.raises(ValueError):
        vclay.dnurbs_surface(np.zeros((4, 3)))

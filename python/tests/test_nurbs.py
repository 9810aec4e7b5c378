"""Evaluation against NURBS-Python (geomdl) on random rational models, derivatives against
finite differences, knot insertion and degree elevation keep the shape, model files round trip."""

import numpy as np
import pytest

import vclay

geomdl = pytest.importorskip("geomdl")
from geomdl import NURBS  # noqa: E402


def clamped_knots(rng, n, p):
    inner = np.sort(rng.uniform(0.0, 1.0, n - p - 1))
    return np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])


def tol(points):
    return 1e-9 * max(1.0, float(np.abs(points).max()))


@pytest.mark.parametrize("seed", range(4))
def test_curve_matches_geomdl(seed):
    rng = np.random.default_rng(seed)
    p, n = int(rng.integers(1, 5)), int(rng.integers(6, 12))
    knots = clamped_knots(rng, n, p)
    cp = rng.normal(size=(n, 3))
    w = rng.uniform(0.3, 3.0, n)
    c = vclay.Curve(p, knots, cp, w)
    g = NURBS.Curve()
    g.degree = p
    g.ctrlptsw = [list(q * wi) + [wi] for q, wi in zip(cp, w)]
    g.knotvector = list(knots)
    u = rng.uniform(0.0, 1.0, 200)
    ours = c.evaluate(u)
    ref = np.array([g.evaluate_single(float(x)) for x in u])
    assert ours.shape == (200, 3)
    np.testing.assert_allclose(ours, ref, atol=tol(ref), rtol=0)
    # First derivatives too.
    d = c.derivatives(u[:20], 1)
    dref = np.array([g.derivatives(float(x), 1)[1] for x in u[:20]])
    np.testing.assert_allclose(d[:, 1], dref, atol=1e-8 * max(1, np.abs(dref).max()), rtol=0)


@pytest.mark.parametrize("seed", range(4))
def test_surface_matches_geomdl(seed):
    rng = np.random.default_rng(100 + seed)
    p, q = int(rng.integers(1, 4)), int(rng.integers(1, 4))
    nu, nv = int(rng.integers(5, 9)), int(rng.integers(5, 9))
    ku, kv = clamped_knots(rng, nu, p), clamped_knots(rng, nv, q)
    cp = rng.normal(size=(nu, nv, 3))
    w = rng.uniform(0.3, 3.0, (nu, nv))
    s = vclay.Surface((p, q), (ku, kv), cp, w)
    g = NURBS.Surface()
    g.degree_u, g.degree_v = p, q
    g.ctrlpts_size_u, g.ctrlpts_size_v = nu, nv
    pw = np.concatenate([cp * w[..., None], w[..., None]], axis=2).reshape(-1, 4)
    g.ctrlptsw = pw.tolist()
    g.knotvector_u, g.knotvector_v = list(ku), list(kv)
    uv = rng.uniform(0.0, 1.0, (300, 2))
    ours = s.evaluate(uv)
    ref = np.array(g.evaluate_list([tuple(map(float, t)) for t in uv]))
    np.testing.assert_allclose(ours, ref, atol=tol(ref), rtol=0)
    d = s.derivatives(uv[:10], 1)
    for k, t in enumerate(uv[:10]):
        skl = g.derivatives(float(t[0]), float(t[1]), 1)
        np.testing.assert_allclose(d[k, 1, 0], skl[1][0], atol=1e-8 * max(1, np.abs(skl[1][0]).max()))
        np.testing.assert_allclose(d[k, 0, 1], skl[0][1], atol=1e-8 * max(1, np.abs(skl[0][1]).max()))


@pytest.mark.parametrize("seed", range(2))
def test_volume_matches_geomdl(seed):
    rng = np.random.default_rng(200 + seed)
    deg = [int(x) for x in rng.integers(1, 3, 3)]
    dims = [int(x) for x in rng.integers(4, 6, 3)]
    kvs = [clamped_knots(rng, n, p) for n, p in zip(dims, deg)]
    cp = rng.normal(size=(*dims, 3))
    w = rng.uniform(0.3, 3.0, dims)
    v = vclay.Volume(deg, kvs, cp, w)
    g = NURBS.Volume()
    g.degree_u, g.degree_v, g.degree_w = deg
    g.ctrlpts_size_u, g.ctrlpts_size_v, g.ctrlpts_size_w = dims
    # geomdl volumes run v fastest, then u, then w.
    pw = np.concatenate([cp * w[..., None], w[..., None]], axis=3)
    g.ctrlptsw = pw.transpose(2, 0, 1, 3).reshape(-1, 4).tolist()
    g.knotvector_u, g.knotvector_v, g.knotvector_w = (list(k) for k in kvs)
    t = rng.uniform(0.0, 1.0, (100, 3))
    ours = v.evaluate(t)
    ref = np.array([g.evaluate_single(tuple(map(float, x))) for x in t])
    np.testing.assert_allclose(ours, ref, atol=tol(ref), rtol=0)


def test_point_equals_evaluate_and_parallel_path(rng):
    s = vclay.Surface((3, 3), (clamped_knots(rng, 8, 3), clamped_knots(rng, 8, 3)),
                      rng.normal(size=(8, 8, 3)), rng.uniform(0.5, 2, (8, 8)))
    uv = rng.uniform(0, 1, (5000, 2))  # above the parallel threshold
    pts = s.evaluate(uv)
    for k in (0, 1234, 4999):
        assert np.array_equal(pts[k], s.point(*uv[k]))
    # Non-contiguous and integer input are accepted.
    np.testing.assert_array_equal(s.evaluate(np.asfortranarray(uv[:10])), pts[:10])


def test_evaluate_grid_with_and_without_out(rng):
    s = vclay.Surface((3, 2), (clamped_knots(rng, 8, 3), clamped_knots(rng, 7, 2)),
                      rng.normal(size=(8, 7, 3)), rng.uniform(0.5, 2, (8, 7)))
    u, v = np.linspace(0, 1, 90), rng.uniform(0, 1, 70)  # above the parallel threshold
    g = s.evaluate_grid(u, v)
    assert g.shape == (90, 70, 3) and g.dtype == np.float64
    uv = np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1).reshape(-1, 2)
    np.testing.assert_allclose(g.reshape(-1, 3), s.evaluate(uv), atol=1e-12, rtol=0)
    out = np.full((90, 70, 3), np.nan)
    r = s.evaluate_grid(u, v, out=out)
    assert r is out
    np.testing.assert_array_equal(out, g)
    with pytest.raises(ValueError, match="shape"):
        s.evaluate_grid(u, v, out=np.empty((70, 90, 3)))
    with pytest.raises(ValueError, match="C-contiguous"):
        s.evaluate_grid(u, v, out=np.empty((90, 70, 3), order="F"))
    with pytest.raises(ValueError, match="float64"):
        s.evaluate_grid(u, v, out=np.empty((90, 70, 3), dtype=np.float32))
    ro = np.empty((90, 70, 3))
    ro.flags.writeable = False
    with pytest.raises(ValueError, match="writeable"):
        s.evaluate_grid(u, v, out=ro)
    with pytest.raises(vclay.GeometryError):
        s.evaluate_grid([0.5, 1.5], v, out=np.empty((2, 70, 3)))


def test_derivatives_match_finite_differences(rng):
    c = vclay.Curve(3, clamped_knots(rng, 9, 3), rng.normal(size=(9, 3)), rng.uniform(0.5, 2, 9))
    u = np.array([0.21, 0.5, 0.77])
    d = c.derivatives(u, 2)
    h = 1e-6
    fd = (c.evaluate(u + h) - c.evaluate(u - h)) / (2 * h)
    np.testing.assert_allclose(d[:, 1], fd, rtol=1e-5, atol=1e-6)
    assert d.shape == (3, 3, 3)
    np.testing.assert_array_equal(d[:, 0], c.evaluate(u))


def test_refinement_keeps_the_shape(rng):
    s = vclay.Surface((2, 3), (clamped_knots(rng, 6, 2), clamped_knots(rng, 7, 3)),
                      rng.normal(size=(6, 7, 3)), rng.uniform(0.5, 2, (6, 7)))
    uv = rng.uniform(0, 1, (200, 2))
    before = s.evaluate(uv)
    k = s.insert_knot(0.37, times=2, axis=1)
    assert isinstance(k, vclay.Surface)
    assert k.control_points.shape == (6, 9, 3)
    e = s.elevate_degree(times=1, axis=0)
    assert e.degree == [3, 3]
    np.testing.assert_allclose(k.evaluate(uv), before, atol=1e-12)
    np.testing.assert_allclose(e.evaluate(uv), before, atol=1e-12)


def test_model_file_round_trip(tmp_path, rng):
    c = vclay.Curve(2, [0, 0, 0, 0.5, 1, 1, 1], rng.normal(size=(4, 3)), [1, 2, 1, 1])
    s = vclay.Surface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), rng.normal(size=(2, 2, 3)))
    path = tmp_path / "m.json"
    vclay.save(path, [c, s])
    back = vclay.load(path)
    assert [type(e) for e in back] == [vclay.Curve, vclay.Surface]
    np.testing.assert_array_equal(back[0].control_points, c.control_points)
    np.testing.assert_array_equal(back[1].evaluate([[0.3, 0.4]]), s.evaluate([[0.3, 0.4]]))
    # Exchange formats by extension; a geomdl file reads back through load.
    # geomdl files hold one kind of shape.
    vclay.save(tmp_path / "s.json", [s])
    vclay.convert(tmp_path / "s.json", tmp_path / "m.geomdl.json")
    g = vclay.load(tmp_path / "m.geomdl.json")
    np.testing.assert_allclose(g[0].evaluate([[0.3, 0.4]]), s.evaluate([[0.3, 0.4]]), atol=1e-12)
    vclay.convert(path, tmp_path / "m.step")
    assert (tmp_path / "m.step").read_text().startswith("ISO-10303-21")
    vclay.convert(path, tmp_path / "m.obj")
    v, t, n = vclay.read_mesh(tmp_path / "m.obj")
    assert v.shape[1] == 3 and t.shape[1] == 3 and len(t) > 0


def test_tessellate_and_render(tmp_path, rng):
    s = vclay.Surface((2, 2), ([0, 0, 0, 1, 1, 1],) * 2, rng.normal(size=(3, 3, 3)))
    v, t, n = s.tessellate(8)
    assert v.shape == (64, 3) and n.shape == (64, 3)
    out = tmp_path / "s.png"
    vclay.render([s], out, size=(64, 48))
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    vclay.render((v, t), tmp_path / "m.png", size=(32, 32), view="top")
    assert (tmp_path / "m.png").stat().st_size > 0

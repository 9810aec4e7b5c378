"""Sizes never kill the interpreter (issue 32 item 1): work whose estimate is over the memory
limit raises `MemoryLimitError` (a `VclayError` and a `MemoryError`, as numpy raises) before
anything is allocated, with the estimates of `vclay --max-memory` (docs/limits.md)."""

import numpy as np
import pytest

import vclay


def surface():
    k = [0, 0, 0, 0, 1, 1, 1, 1]
    g = np.linspace(0, 1, 4)
    X, Y = np.meshgrid(g, g, indexing="ij")
    return vclay.Surface((3, 3), (k, k), np.stack([X, Y, X * Y], -1))


def test_memory_limit_error_is_a_memory_error_and_a_vclay_error():
    assert issubclass(vclay.MemoryLimitError, MemoryError)
    assert issubclass(vclay.MemoryLimitError, vclay.VclayError)
    assert vclay.max_memory() == vclay.DEFAULT_MAX_MEMORY == 4 << 30


def test_grids_and_tessellations_too_large_raise_before_allocating():
    s = surface()
    big = np.linspace(0, 1, 100000)
    with pytest.raises(MemoryError, match=r"evaluate_grid: u \(100000 values\) x v \(100000 values\) needs about 240.0 GB"):
        s.evaluate_grid(big, big)
    with pytest.raises(vclay.MemoryLimitError, match=r"samples=100000 .* needs about 2560.0 GB"):
        s.tessellate(100000)
    with pytest.raises(MemoryError, match="derivatives: order=31"):
        s.derivatives(np.zeros((10**6, 2)), 31)
    # A broadcast view stands for 4e10 values without memory: refused before numpy copies it.
    view = np.broadcast_to(np.int64(0), (2 * 10**10, 2))
    with pytest.raises(MemoryError, match=r"params \(shape \[20000000000, 2\]\)"):
        s.evaluate(view)
    # Within the limit these work.
    assert s.evaluate_grid(big[:100], big[:50]).shape == (100, 50, 3)


def test_ffd_lattices_too_large_raise():
    with pytest.raises(MemoryError, match=r"control_points=\[100000, 100000, 100000\] needs about 9.6e16 B"):
        vclay.Ffd([0, 0, 0], [1, 1, 1], control_points=100000)
    with pytest.raises(vclay.MemoryLimitError, match=r"control_points=\[1000, 1000, 1000\]"):
        vclay.Ffd([0, 0, 0], [1, 1, 1], control_points=1000)
    with pytest.raises(MemoryError):
        vclay.Ffd.enclosing(np.random.default_rng(0).random((10, 3)), control_points=(5000, 5000, 50))


def test_other_sizes(tmp_path):
    with pytest.raises(MemoryError, match=r"size=\(8192, 8192\)"):
        vclay.set_max_memory(10**8)
        try:
            vclay.render([surface()], tmp_path / "x.png", size=(8192, 8192))
        finally:
            vclay.set_max_memory(None)
    with pytest.raises(MemoryError, match="samples=20000"):
        vclay.save(tmp_path / "x.obj", [surface()], samples=20000)
    lat = vclay.Lattice.primitive("box")
    vclay.set_max_memory(10**6)
    try:
        with pytest.raises(MemoryError, match="levels=3"):
            lat.subdivide(3)
    finally:
        vclay.set_max_memory(None)
    assert vclay.max_memory() == vclay.DEFAULT_MAX_MEMORY


def test_the_limit_is_settable():
    s = surface()
    vclay.set_max_memory(1000)
    try:
        with pytest.raises(MemoryError, match="limit of 1 kB"):
            s.evaluate_grid(np.linspace(0, 1, 100), np.linspace(0, 1, 100))
    finally:
        vclay.set_max_memory(None)
    with pytest.raises(ValueError, match="nbytes"):
        vclay.set_max_memory(-1)


def test_primitives_and_dnurbs_nets_too_large_raise():
    with pytest.raises(MemoryError, match='primitive "box:1000x1000x1000"'):
        vclay.Lattice.primitive("box:1000x1000x1000")
    with pytest.raises(MemoryError, match="box:200x200x200"):
        vclay.Lattice.primitive("box:200x200x200")
    assert len(vclay.Lattice.primitive("box:5x5x5")) == 64
    with pytest.raises(vclay.ArgumentError, match="points: 2000 control points along a direction"):
        vclay.dnurbs_surface(np.zeros((2000, 4, 3)))

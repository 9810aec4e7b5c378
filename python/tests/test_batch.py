"""Batch: a material sweep fanned out over a Dask LocalCluster of processes gives the same
results, bit for bit, as the serial loop (python/examples/dask_sweep.py)."""

import sys
from pathlib import Path

import pytest

pytest.importorskip("dask.distributed")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import dask_sweep  # noqa: E402


def test_dask_sweep_equals_serial_loop():
    values = [60.0, 100.0, 140.0]
    steps = 10
    client = dask_sweep.local_client(2)
    try:
        results = dask_sweep.sweep(client, dask_sweep.SCENARIO, values, steps)
    finally:
        client.close()
        client.cluster.close()
    serial = dask_sweep.serial(dask_sweep.SCENARIO, values, steps)
    assert [r["stiffness"] for r in results] == values
    assert dask_sweep.same(results, serial)
    # Different materials give different shapes.
    assert not (results[0]["data_points"] == results[2]["data_points"]).all()

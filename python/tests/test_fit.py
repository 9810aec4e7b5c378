"""fit_surface (issue 20): a noisy wave scan is fitted to the noise level; bad clouds raise."""

import numpy as np
import pytest

import vclay


def test_noisy_wave_is_fitted_to_the_noise_level(rng):
    xy = rng.uniform(-1, 1, (5000, 2))
    z = 0.15 * np.sin(2 * xy[:, 0]) * np.cos(1.5 * xy[:, 1]) + rng.normal(0, 0.002, 5000)
    pts = np.column_stack([xy, z])
    surf, report = vclay.fit_surface(pts, grid=(12, 12))
    assert isinstance(surf, vclay.Surface)
    assert report["robust_mode"] == "auto" and not report["outliers_detected"]
    assert report["points"] == 5000 and report["grid"] == [12, 12]
    assert 0.0015 < report["rms"] < 0.0022
    # The surface follows the wave: its points lie on it to well below the noise.
    s = surf.evaluate(rng.uniform(0.1, 0.9, (200, 2)))
    dev = s[:, 2] - 0.15 * np.sin(2 * s[:, 0]) * np.cos(1.5 * s[:, 1])
    assert np.abs(dev).max() < 0.002


def test_robust_option_and_errors(rng):
    xy = rng.uniform(-1, 1, (3000, 2))
    pts = np.column_stack([xy, 0.1 * xy[:, 0] ** 2 + rng.normal(0, 0.002, 3000)])
    pts[::20, 2] += 0.5
    _, report = vclay.fit_surface(pts, grid=(8, 8), robust="tukey")
    assert report["robust"] == "tukey" and 150 <= report["outliers"] <= 160
    # The default ("auto", issue 29) finds the 5 % gross outliers after its first round and
    # goes on as "tukey"; "none" (or None) keeps plain least squares.
    auto, report = vclay.fit_surface(pts, grid=(8, 8))
    assert report["robust_mode"] == "auto" and report["outliers_detected"]
    assert report["robust"] == "tukey" and 150 <= report["outliers"] <= 160
    for plain in ("none", None):
        _, report = vclay.fit_surface(pts, grid=(8, 8), robust=plain)
        assert report["robust_mode"] == "none" and report["robust"] is None
        assert not report["outliers_detected"]
    with pytest.raises(vclay.GeometryError, match="on a line"):
        vclay.fit_surface(np.column_stack([xy[:, 0], xy[:, 0], xy[:, 0]]), grid=(8, 8))
    with pytest.raises(vclay.GeometryError, match="unknown robust mode"):
        vclay.fit_surface(pts, robust="cauchy")

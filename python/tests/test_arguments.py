"""Errors name the argument, not a hidden file (issue 32 items 6 and 10): `dnurbs_surface`
works with its defaults; a bad value raises `ArgumentError` (a `VclayError` and a `ValueError`)
naming the argument, with no `<dnurbs_surface>:0:` file prefix; negative counts name the
argument instead of "OverflowError: can't convert negative int to unsigned"."""

import pytest

import vclay
from test_dnurbs import flat_sheet


def test_defaults_work():
    s = vclay.dnurbs_surface(flat_sheet())
    assert {p["name"]: p["value"] for p in s.params()}["dt"] == 0.01
    s.step(2)


@pytest.mark.parametrize("kw, arg", [
    ({"engine": "bogus"}, "engine"),
    ({"material": {"preset": "nope"}}, 'material\\["preset"\\]'),
    ({"material": {"mu": -1.0}}, 'material\\["mu"\\]'),
    ({"reference": "x"}, "reference"),
    ({"fix": [1000]}, "fix"),
    ({"dt": -1.0}, "dt"),
    ({"material": {"bogus": 1}}, "material: bogus"),
])
def test_bad_values_name_the_argument(kw, arg):
    with pytest.raises(vclay.ArgumentError, match=f"^dnurbs_surface: {arg}|^material: bogus") as e:
        vclay.dnurbs_surface(flat_sheet(), **kw)
    assert isinstance(e.value, ValueError) and isinstance(e.value, vclay.VclayError)
    assert "<dnurbs_surface>" not in str(e.value) and ":0:" not in str(e.value)

"""eyeshell.optics: the schematic eye's best-focus surfaces as arrays."""

import numpy as np
import pytest

import eyeshell


def test_optics_returns_the_surfaces_as_arrays():
    o = eyeshell.optics(None, **{"optics.focus": "sagittal", "optics.pupil": 1})
    assert o["eye"] == "atchison-2006" and o["criterion"] == "sagittal"
    assert o["z"].shape == o["r"].shape == (82,)
    assert list(np.unique(o["wavelength_nm"])) == [400.0, 600.0]
    # On the axis at 400 nm: 23.038 mm (docs/optics.md); red 0.6 mm behind.
    assert abs(o["z"][0] - 23.038) < 2e-3 and o["r"][0] == 0.0
    assert 0.5 < o["z"][41] - o["z"][0] < 0.7
    # The sagittal criterion is the sagittal focal line.
    assert o["field_deg"][40] == 40.0 and 0.44 < o["phi_max"][0] < 0.47
    # 4 rays across the 1 mm pupil suffice: 8 traced and mirrored, and the chief ray, a focus.
    assert o["rays_traced"] == 82 * 9


def test_bad_optics_keys_are_input_errors_naming_the_key():
    with pytest.raises(eyeshell.InputError, match="optics.pupil"):
        eyeshell.optics(None, **{"optics.pupil": 12})
    with pytest.raises(eyeshell.InputError, match="optics.max_field = 80 cannot be traced"):
        eyeshell.optics(None, **{"optics.pupil": 8, "optics.max_field": 80})

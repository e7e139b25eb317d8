"""eyeshell.optics: the schematic eye's best-focus surfaces as arrays."""

import numpy as np
import pytest

import eyeshell
from conftest import SCENES, read_csv


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


def test_optics_gives_the_refraction_without_growing(cli, tmp_path):
    """eyeshell.optics(...)["refraction"] is what `eyeshell optics` writes: the naked eye's
    and, through the −2 D spectacle lens, the over-refraction, at the pole and every field,
    bit for bit; the naked eye's pole is Solution.refraction_D."""
    scene = SCENES / "eyewear" / "single-vision.toml"
    r = eyeshell.optics(scene, solver__nodes=101)["refraction"]
    assert len(r) == 1 and r[0]["t"] == 0.0
    assert r[0]["refraction_D"] == eyeshell.solve(scene, solver__nodes=101).refraction_D
    (through,) = r[0]["through_lenses"]
    assert through["image_power_D"] is None
    assert abs(through["refraction_D"] - r[0]["refraction_D"] - 2.0) < 1e-5
    cli("optics", scene, "--set", "solver.nodes=101", "--out", tmp_path / "o", "--quiet")
    rows = read_csv(tmp_path / "o" / "peripheral.csv")
    naked = [float(x) for x, t in zip(rows["refraction_D"], rows["through"]) if t == "naked"]
    worn = [float(x) for x, t in zip(rows["refraction_D"], rows["through"]) if t == "lenses"]
    assert naked == r[0]["peripheral"]["refraction_D"].tolist()
    assert worn == through["peripheral"]["refraction_D"].tolist()
    assert r[0]["peripheral"]["field_deg"].tolist() == [5.0 * k for k in range(9)]

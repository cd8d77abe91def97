"""The campaign's ``[thermal]`` block as models.thermal's reference state (SEED-NOTES 8)."""

from __future__ import annotations

from pathlib import Path

import pytest

from models.thermal.reference_state import ThermalReference
from rigtools.campaign import load_campaign, thermal_reference
from rigtools.errors import CampaignError

HEAD = """\
[campaign]
name = "thermal"
gear_set = "fzg-c"
"""
RUN = """
[[run]]
id = "A"
file = "runs/a.mcap"
oil_temperature_C = 88.0
"""


def manifest(tmp_path: Path, thermal: str) -> Path:
    p = tmp_path / "c.toml"
    p.write_text(HEAD + thermal + RUN)
    return p


def test_fixed_centre_distance(tmp_path):
    c = load_campaign(manifest(tmp_path, "\n[thermal]\nreference_temperature_C = 20.0\n"
                                         'housing = "fixed-centre-distance"\n'))
    ref = thermal_reference(c)
    assert ref == ThermalReference(20.0, "fixed-centre-distance")
    assert ref.centre_distance_change(0.0915, 1.15e-5) == 0.0


def test_follows_oil_takes_the_runs_oil_temperature(tmp_path):
    c = load_campaign(manifest(tmp_path, "\n[thermal]\nreference_temperature_C = 20.0\n"
                                         'housing = "follows-oil"\n'))
    oil = c.runs[0].oil_temperature_C
    assert oil == 88.0
    ref = thermal_reference(c, oil_temperature_C=oil)
    assert (ref.reference_temperature_C, ref.housing, ref.oil_temperature_C) == (
        20.0, "follows-oil", 88.0)
    # Delta a = xi (t_oil - t_ref) a' (models.thermal.reference_state)
    assert ref.centre_distance_change(0.0915, 1.15e-5) == pytest.approx(
        1.15e-5 * 68.0 * 0.0915, rel=1e-12)


def test_housing_left_out_is_the_models_default(tmp_path):
    c = load_campaign(manifest(tmp_path, "\n[thermal]\nreference_temperature_C = 25.0\n"))
    assert thermal_reference(c).housing == ThermalReference(25.0).housing


def test_follows_oil_without_an_oil_temperature_names_the_thermal_line(tmp_path):
    p = manifest(tmp_path, '\n[thermal]\nreference_temperature_C = 20.0\nhousing = "follows-oil"\n')
    with pytest.raises(CampaignError, match=r"c\.toml at line 5: expected a \[thermal\] block "
                       r"the thermal model accepts, `oil_temperature_C` is required"):
        thermal_reference(load_campaign(p))


@pytest.mark.parametrize("thermal", ["", '\n[thermal]\nhousing = "follows-oil"\n'])
def test_no_reference_temperature_is_a_campaign_error(tmp_path, thermal):
    p = manifest(tmp_path, thermal)
    with pytest.raises(CampaignError, match=r"expected key 'reference_temperature_C' in "
                       r"\[thermal\].*found none") as exc:
        thermal_reference(load_campaign(p))
    assert str(exc.value).startswith(str(p))
    assert (exc.value.position is None) == (thermal == "")

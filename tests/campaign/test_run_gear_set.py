"""``[[run]] gear_set``: a run on another gear pair than the campaign's (issue 20).

The observations use the run's teeth and pair (``test_runup_observation.py`` reads harmonics
at the Kahraman-Blankenship orders in an FZG-C campaign); here: loading, errors naming key and
line, :meth:`Campaign.gear_for`, the resolved configuration, and the natural-frequency
calibration leaving such runs out with a note.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest

import rigtools.calibration.campaign_inputs as campaign_inputs
from models.geometry.gear_sets import gear_set_path
from rigtools.calibration.campaign_inputs import campaign_gear_rows
from rigtools.campaign import load_campaign, to_frame
from rigtools.campaign.observe import observations_metadata
from rigtools.errors import CampaignError

CAMPAIGN = """\
[campaign]
name = "two pairs"
gear_set = "fzg-c"

[[run]]
id = "F1"
file = "f1.mcap"
torque_Nm = 100.0

[[run]]
id = "KB-{stem}"
file = "kb_*.mcap"
torque_Nm = 300.0
gear_set = "kahraman-blankenship"

[[run]]
id = "F2"
file = "f2.mcap"
gear_set = "fzg-c"
"""


@pytest.fixture()
def campaign_file(tmp_path: Path) -> Path:
    for name in ("kb_a.mcap", "kb_b.mcap"):
        (tmp_path / name).write_bytes(b"")
    p = tmp_path / "c.toml"
    p.write_text(CAMPAIGN)
    return p


def test_a_run_gear_set_overrides_the_campaigns(campaign_file):
    camp = load_campaign(campaign_file)
    assert [r.id for r in camp.runs] == ["F1", "KB-kb_a", "KB-kb_b", "F2"]
    assert camp.gear_for("F1") is camp.gear and camp.gear.name == "fzg-c"
    kb = camp.gear_for("KB-kb_a")
    assert kb.name == "kahraman-blankenship" and int(kb.pair.pinion.teeth) == 50
    assert camp.gear_for("KB-kb_b") is kb  # loaded once
    assert camp.gear_set_for("KB-kb_b") == "kahraman-blankenship"
    assert camp.gear_set_for("F1") == "fzg-c"
    assert camp.run("KB-kb_a").gear_set_path == str(gear_set_path("kahraman-blankenship"))
    # naming the campaign's own gear set keeps the run on it
    assert [camp.on_campaign_gear(r.id) for r in camp.runs] == [True, False, False, True]
    assert camp.pinion_teeth == 16
    with pytest.raises(KeyError):
        camp.gear_for("nope")
    runs = {r["id"]: r for r in camp.to_dict()["run"]}
    assert runs["KB-kb_a"]["gear_set"] == "kahraman-blankenship"
    assert "gear_set" not in runs["F1"]
    meta = observations_metadata(camp, [])
    assert meta["gear"]["z1"] == 16
    assert meta["run_gears"]["KB-kb_a"] == {"gear_set": "kahraman-blankenship",
                                            "name": "kahraman-blankenship", "z1": 50, "z2": 50}


def test_a_gear_set_file_relative_to_the_campaign(tmp_path):
    (tmp_path / "gears").mkdir()
    (tmp_path / "gears" / "kb.toml").write_text(
        gear_set_path("kahraman-blankenship").read_text())
    (tmp_path / "c.toml").write_text(CAMPAIGN.replace('gear_set = "kahraman-blankenship"',
                                                      'gear_set = "gears/kb.toml"')
                                     .replace('file = "kb_*.mcap"', 'file = "kb.mcap"'))
    camp = load_campaign(tmp_path / "c.toml")
    assert camp.gear_for("KB-{stem}").name == "kahraman-blankenship"
    assert camp.run("KB-{stem}").gear_set_path == str(tmp_path / "gears" / "kb.toml")


@pytest.mark.parametrize(("value", "fragments"), [
    ('"no-such-gears"', ["c.toml at line 14", "run.gear_set to be a shipped gear set",
                         "'no-such-gears'"]),
    ('"gears/missing.toml"', ["c.toml at line 14", "run.gear_set to be a shipped gear set",
                              "no such file"]),
    ('""', ["c.toml at line 14", "run[1].gear_set"]),
    ("3", ["c.toml at line 14", "run[1].gear_set"]),
])
def test_a_bad_run_gear_set_names_key_and_line(campaign_file, value, fragments):
    campaign_file.write_text(CAMPAIGN.replace('gear_set = "kahraman-blankenship"',
                                              f"gear_set = {value}"))
    with pytest.raises(CampaignError) as err:
        load_campaign(campaign_file)
    for f in fragments:
        assert f in str(err.value)


def test_a_gear_set_that_does_not_load_names_the_run_key(tmp_path, campaign_file):
    (tmp_path / "bad.toml").write_text("this is = not a gear set\n")
    campaign_file.write_text(CAMPAIGN.replace('gear_set = "kahraman-blankenship"',
                                              'gear_set = "bad.toml"'))
    with pytest.raises(CampaignError, match=r"c\.toml at line 14: expected a gear set that "
                                            r"loads.*run\.gear_set = 'bad\.toml'"):
        load_campaign(campaign_file)


def _rows(run_id: str) -> dict:
    return {"campaign": "two pairs", "run_id": run_id, "channel": None, "quantity": "run",
            "status": "ok", "quality_flags": "", "message": "", "source_file": "x",
            "rigtools_version": "0"}


def test_the_natural_frequency_calibration_leaves_other_pairs_out(campaign_file, monkeypatch):
    camp = load_campaign(campaign_file)
    table = to_frame([_rows(r) for r in ("F1", "KB-kb_a", "KB-kb_b", "F2")])
    kept, left = campaign_gear_rows(camp, table)
    assert list(kept.run_id) == ["F1", "F2"]
    assert list(left) == ["KB-kb_a", "KB-kb_b"]
    assert "'kahraman-blankenship'" in left["KB-kb_a"] and "'fzg-c'" in left["KB-kb_a"]
    same, none = campaign_gear_rows(camp, table[table.run_id.isin(["F1", "F2"])])
    assert none == {} and list(same.run_id) == ["F1", "F2"]

    seen: dict[str, pd.DataFrame] = {}

    def fake(observations, pair, cfg, **kw):
        seen["table"] = observations
        seen["teeth"] = int(pair.pinion.teeth)
        return SimpleNamespace(summary={"warnings": ["w0"]}, warnings=("w0",))

    monkeypatch.setattr(campaign_inputs, "calibrate_observations", fake)
    monkeypatch.setattr(campaign_inputs, "replace",
                        lambda obj, **kw: SimpleNamespace(**{**vars(obj), **kw}))
    result = campaign_inputs.calibrate(camp, table)
    assert list(seen["table"].run_id) == ["F1", "F2"] and seen["teeth"] == 16
    assert result.warnings[0].startswith("run 'KB-kb_a' left out: on gear set "
                                         "'kahraman-blankenship'")
    assert result.warnings[-1] == "w0" and len(result.warnings) == 3
    assert result.summary["warnings"] == list(result.warnings)

"""Conditions from a CSV sheet (``[campaign] conditions``): values fill what the runs leave out.

Every error names the sheet, the row (1-based, the header is row 1) and the column; a conflict
with a ``[[run]]`` names both places. Run files need not exist to load a campaign.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rigtools.campaign import load_campaign
from rigtools.campaign.conditions_sheet import read_conditions_sheet
from rigtools.errors import CampaignError

CAMPAIGN = """\
[campaign]
name = "sheet study"
gear_set = "fzg-c"
conditions = "sheets/runs.csv"

[[run]]
id = "A"
file = "runs/a.mcap"
torque_Nm = 302.0

[[run]]
id = "B"
file = "runs/b.blf"
bulk_temperature_C = "BulkTemp_C"

[[run]]
id = "C"
file = "runs/c.blf"

[[run]]
id = "G-{stem}"
file = "runs/g_*.mcap"
"""

SHEET = """\
run_id,torque_Nm,bulk_temperature_C,oil_temperature_C,speed_rpm,notes
A,302,90.0,85.5,1500,"first run, after the oil change"

B,183.4,,80,1.5e3,
G-g_60c,94.1,60,55,1500,glob run
"""


def make(tmp_path: Path, sheet: str = SHEET, campaign: str = CAMPAIGN) -> Path:
    (tmp_path / "sheets").mkdir(exist_ok=True)
    (tmp_path / "runs").mkdir(exist_ok=True)
    for name in ("g_60c", "g_90c"):
        (tmp_path / "runs" / f"{name}.mcap").write_bytes(b"")
    (tmp_path / "sheets" / "runs.csv").write_text(sheet, encoding="utf-8")
    p = tmp_path / "study.toml"
    p.write_text(campaign, encoding="utf-8")
    return p


def test_the_sheet_fills_what_the_runs_leave_out(tmp_path):
    c = load_campaign(make(tmp_path))
    a, b, cc, g60, g90 = c.runs
    assert a.conditions() == {"torque_Nm": 302.0, "bulk_temperature_C": 90.0,
                              "oil_temperature_C": 85.5, "speed_rpm": 1500.0}
    assert a.notes == "first run, after the oil change"
    # an empty cell gives nothing; the run's signal name is kept
    assert b.conditions() == {"torque_Nm": 183.4, "bulk_temperature_C": "BulkTemp_C",
                              "oil_temperature_C": 80.0, "speed_rpm": 1500.0}
    assert b.notes == ""
    # a run the sheet does not name is kept as it is
    assert cc.conditions() == dict.fromkeys(cc.conditions())
    # glob runs are named by their expanded ids
    assert g60.id == "G-g_60c" and g60.torque_Nm == 94.1 and g60.notes == "glob run"
    assert g90.torque_Nm is None
    assert c.conditions_sheet == tmp_path / "sheets" / "runs.csv"
    assert c.to_dict()["campaign"]["conditions"] == str(tmp_path / "sheets" / "runs.csv")
    assert c.to_dict()["run"][0]["oil_temperature_C"] == 85.5


def test_columns_in_any_order_with_a_bom_and_spaces(tmp_path):
    sheet = "\ufeff speed_rpm , run_id\n1200 , C\n"
    c = load_campaign(make(tmp_path, sheet))
    assert c.run("C").speed_rpm == 1200.0 and c.run("A").speed_rpm is None


def test_the_sheet_is_read_alone_with_row_numbers(tmp_path):
    make(tmp_path)
    s = read_conditions_sheet(tmp_path / "sheets" / "runs.csv",
                              ("torque_Nm", "bulk_temperature_C", "oil_temperature_C",
                               "speed_rpm"))
    assert s.columns[0] == "run_id" and list(s.rows) == ["A", "B", "G-g_60c"]
    assert [r.row for r in s.rows.values()] == [2, 4, 5]  # the blank line is row 3
    assert s.rows["B"].values == {"torque_Nm": 183.4, "oil_temperature_C": 80.0,
                                  "speed_rpm": 1500.0}


def test_a_value_given_twice_alike_is_fine(tmp_path):
    sheet = "run_id,torque_Nm\nA,302\n"  # 302 in the sheet, 302.0 in the campaign
    assert load_campaign(make(tmp_path, sheet)).run("A").torque_Nm == 302.0


_CSV = re.escape("runs.csv")

_BAD_SHEETS = [
    # (sheet, error naming ...)
    ("run_id,torque_nm\nA,1\n",
     rf"{_CSV} at row 1, column 'torque_nm': expected one of the columns run_id, torque_Nm, "
     r".*notes, found unknown column 'torque_nm' \(did you mean 'torque_Nm'\?\)"),
    ("run_id,speed_rpm,speed_rpm\nA,1,2\n",
     rf"{_CSV} at row 1, column 'speed_rpm': expected each column once"),
    ("torque_Nm,notes\n1,x\n", rf"{_CSV} at row 1: expected a column 'run_id'"),
    ("", rf"{_CSV} at row 1: expected a header row with run_id, found an empty file"),
    ("run_id,torque_Nm\nA,302\nB,lots\n",
     rf"{_CSV} at row 3, column 'torque_Nm': expected a number, found 'lots'"),
    ("run_id,torque_Nm\nB,3,5\n",
     rf"{_CSV} at row 2: expected at most 2 cells \(the header's\), found 3 cells"),
    ("run_id,oil_temperature_C\nB,nan\n",
     rf"{_CSV} at row 2, column 'oil_temperature_C': expected a number, found 'nan'"),
    ("run_id,oil_temperature_C\nB,1e999\n",
     rf"{_CSV} at row 2, column 'oil_temperature_C': expected a finite number, found '1e999'"),
    ("run_id,speed_rpm\nB,1_500\n",
     rf"{_CSV} at row 2, column 'speed_rpm': expected a number, found '1_500'"),
    ("run_id,speed_rpm\nB,__import__('os')\n",
     rf"{_CSV} at row 2, column 'speed_rpm': expected a number, found \"__import__\('os'\)\""),
    ("run_id,speed_rpm\nB,1500\n\nB,1500\n",
     rf"{_CSV} at row 4, column 'run_id': expected a run id once, found 'B' again "
     r"\(first in row 2\)"),
    ("run_id,speed_rpm\n,1500\n",
     rf"{_CSV} at row 2, column 'run_id': expected a run id, found an empty cell"),
    ("run_id,speed_rpm\nA,1500\nLS9,1500\n",
     rf"{_CSV} at row 3, column 'run_id': expected a run id of the campaign .*study.toml, "
     r"found 'LS9', not a run of it"),
    ("run_id,speed_rpm\nG-g_6c,1500\n",
     rf"{_CSV} at row 2, column 'run_id': .*found 'G-g_6c' \(did you mean 'G-g_60c'\?\)"),
    ('run_id,notes\nA,"unclosed\n', rf"{_CSV} at row \d: expected CSV"),
]


@pytest.mark.parametrize(("sheet", "match"), _BAD_SHEETS, ids=[m[len(_CSV):][:40]
                                                              for _s, m in _BAD_SHEETS])
def test_bad_sheet_names_the_row_and_column(tmp_path, sheet, match):
    p = make(tmp_path, sheet)
    with pytest.raises(CampaignError, match=match) as exc:
        load_campaign(p)
    assert str(exc.value).startswith(str(tmp_path / "sheets" / "runs.csv"))


def test_a_run_and_the_sheet_disagreeing_names_both_places(tmp_path):
    sheet = "run_id,torque_Nm\nA,300.0\n"
    with pytest.raises(CampaignError, match=(
            r"study\.toml at line 9: expected one value of torque_Nm for run 'A', found 302\.0 "
            rf"here and 300\.0 in .*{_CSV} at row 2, column 'torque_Nm'")):
        load_campaign(make(tmp_path, sheet))
    # a run naming a slow signal and the sheet giving a number
    sheet = "run_id,bulk_temperature_C\nB,70\n"
    with pytest.raises(CampaignError, match=(
            r"study\.toml at line 14: expected one value of bulk_temperature_C for run 'B', "
            rf"found 'BulkTemp_C' here and 70\.0 in .*{_CSV} at row 2")):
        load_campaign(make(tmp_path, sheet))
    # notes too
    campaign = CAMPAIGN.replace('file = "runs/c.blf"', 'file = "runs/c.blf"\nnotes = "mine"')
    with pytest.raises(CampaignError, match=r"at line 19: expected one value of notes for run "
                       r"'C', found 'mine' here and 'theirs' in .*row 2, column 'notes'"):
        load_campaign(make(tmp_path, "run_id,notes\nC,theirs\n", campaign))


def test_a_missing_sheet_names_the_campaign_line(tmp_path):
    p = make(tmp_path)
    (tmp_path / "sheets" / "runs.csv").unlink()
    with pytest.raises(CampaignError, match=r"study\.toml at line 4: expected campaign."
                       r"conditions to name an existing CSV file .*'sheets/runs.csv': no such"):
        load_campaign(p)


def test_an_empty_conditions_key_is_a_schema_error(tmp_path):
    p = make(tmp_path, campaign=CAMPAIGN.replace('"sheets/runs.csv"', '""'))
    with pytest.raises(CampaignError, match=r"at line 4: .*campaign.conditions"):
        load_campaign(p)

"""Run conditions from a CSV sheet (``[campaign] conditions = "runs.csv"``).

The sheet a test engineer already keeps: a header row, then one row per run::

    run_id,torque_Nm,bulk_temperature_C,oil_temperature_C,speed_rpm,notes
    LS9-90C,302.0,90.0,85.5,1500,"first run after the oil change"
    LS7-90C,183.4,90.0,,1500,

``run_id`` is required; the other columns are optional and in any order. An empty cell gives
nothing. The file is read with the :mod:`csv` module (comma separated, ``"`` quoting, UTF-8
with or without a byte-order mark); numbers are plain decimals (``1500``, ``-3.5``,
``1.2e3``), never evaluated. Every error is a :class:`~rigtools.errors.CampaignError` naming
the sheet, the row (1-based, the header is row 1) and the column: an unknown or repeated
column, a row with more cells than the header, a value that is not a finite number, an empty
or repeated ``run_id``. Whether each ``run_id`` is a run of the campaign, and whether the sheet
agrees with the ``[[run]]`` tables, is checked by :func:`rigtools.campaign.load_campaign`.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final

from rigtools.errors import CampaignError

__all__ = ["RUN_ID_COLUMN", "ConditionsSheet", "SheetRow", "read_conditions_sheet"]

#: The one required column.
RUN_ID_COLUMN: Final = "run_id"
#: A plain decimal number (no underscores, no ``nan``/``inf``, no expressions).
_NUMBER: Final = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


@dataclass(frozen=True)
class SheetRow:
    """The values one row of the sheet gives a run.

    Attributes
    ----------
    run_id : str
    row : int
        Row number in the file (1-based, the header is row 1).
    values : dict of str to float or str
        Column -> value, for the non-empty cells only: floats for the numeric columns (in
        the unit the column name carries), str for the text columns.
    """

    run_id: str
    row: int
    values: dict[str, float | str] = field(default_factory=dict)


@dataclass(frozen=True)
class ConditionsSheet:
    """A validated conditions sheet.

    Attributes
    ----------
    path : pathlib.Path
        The CSV file.
    columns : tuple of str
        The header, in file order.
    rows : dict of str to SheetRow
        By run id, in file order.
    """

    path: Path
    columns: tuple[str, ...]
    rows: dict[str, SheetRow]


def _cell_error(path: Path, row: int, column: str, expected: str, found: str) -> CampaignError:
    return CampaignError(path, f"row {row}, column {column!r}", expected, found)


def read_conditions_sheet(path: str | Path, numeric_columns: Sequence[str],
                          text_columns: Sequence[str] = ("notes",)) -> ConditionsSheet:
    """Read and validate a conditions sheet.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file.
    numeric_columns : sequence of str
        Columns holding numbers (finite, in the unit their name carries).
    text_columns : sequence of str
        Columns holding free text.

    Returns
    -------
    ConditionsSheet

    Raises
    ------
    CampaignError
        The file cannot be read or is not CSV; no header or no ``run_id`` column; an unknown
        or repeated column; a row longer than the header; an empty or repeated ``run_id``; a
        numeric cell that is not a finite plain decimal. The message names the file, the row
        (header = row 1) and the column.
    """
    p = Path(path)
    allowed = (RUN_ID_COLUMN, *numeric_columns, *text_columns)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise CampaignError(p, None, "a conditions sheet (CSV)", "no such file") from None
    except IsADirectoryError:
        raise CampaignError(p, None, "a conditions sheet (CSV)", "a directory") from None
    except UnicodeDecodeError as exc:
        raise CampaignError(p, f"byte {exc.start}", "UTF-8 text", "undecodable bytes") from None
    reader = csv.reader(text.splitlines(keepends=True), strict=True)
    rows: dict[str, SheetRow] = {}
    header: list[str] | None = None
    n = 0  # row number as a spreadsheet shows it: one per record, blank lines included
    try:
        for n, record in enumerate(reader, 1):
            if not any(c.strip() for c in record):
                continue  # blank line
            if header is None:
                header = _header(p, n, record, allowed)
                continue
            if len(record) > len(header):
                raise CampaignError(p, f"row {n}", f"at most {len(header)} cells (the header's)",
                                    f"{len(record)} cells")
            cells = {col: record[i].strip() if i < len(record) else ""
                     for i, col in enumerate(header)}
            run_id = cells[RUN_ID_COLUMN]
            if not run_id:
                raise _cell_error(p, n, RUN_ID_COLUMN, "a run id", "an empty cell")
            if run_id in rows:
                raise _cell_error(p, n, RUN_ID_COLUMN, "a run id once",
                                  f"{run_id!r} again (first in row {rows[run_id].row})")
            values: dict[str, float | str] = {}
            for col, cell in cells.items():
                if col == RUN_ID_COLUMN or not cell:
                    continue
                if col in text_columns:
                    values[col] = cell
                    continue
                if not _NUMBER.fullmatch(cell):
                    raise _cell_error(p, n, col, "a number", repr(cell))
                v = float(cell)
                if not math.isfinite(v):
                    raise _cell_error(p, n, col, "a finite number", repr(cell))
                values[col] = v
            rows[run_id] = SheetRow(run_id, n, values)
    except csv.Error as exc:
        raise CampaignError(p, f"row {n + 1}", "CSV", None, str(exc)) from None
    if header is None:
        raise CampaignError(p, "row 1", f"a header row with {RUN_ID_COLUMN}", "an empty file")
    return ConditionsSheet(p, tuple(header), rows)


def _header(p: Path, n: int, record: list[str], allowed: Sequence[str]) -> list[str]:
    header = [c.strip() for c in record]
    seen: set[str] = set()
    for col in header:
        if col not in allowed:
            close = [a for a in allowed if a.lower() == col.lower()]
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise CampaignError(p, f"row {n}, column {col!r}",
                                f"one of the columns {', '.join(allowed)}",
                                f"unknown column {col!r}{hint}")
        if col in seen:
            raise CampaignError(p, f"row {n}, column {col!r}", "each column once",
                                f"{col!r} again")
        seen.add(col)
    if RUN_ID_COLUMN not in seen:
        raise CampaignError(p, f"row {n}", f"a column {RUN_ID_COLUMN!r}",
                            f"the columns {', '.join(header)}")
    return header

"""Campaign manifests: the user's one description of an experiment (TOML).

A campaign names the gear set, says how recordings map to channels, fixes the thermal
reference state and the analysis settings, and lists one ``[[run]]`` per recording with its
conditions as the engineer logged them::

    [campaign]
    name = "FZG-C backlash study"
    gear_set = "fzg-c"                      # a shipped gear set, or a path to the user's own

    [sensors]
    dbc = "rig.dbc"                         # CAN logs; MCAP needs no DBC
    accel = ["accel_1", "accel_2"]          # default: every uniform channel
    speed = "PinionSpeed_rpm"               # slow signal or tacho channel: enables Arms per step

    [thermal]
    reference_temperature_C = 20.0
    housing = "fixed-centre-distance"       # or "follows-oil"

    [analysis]                              # all optional
    nperseg = 4096

    [[run]]
    id = "LS9-90C"
    file = "runs/ls9_90c.mcap"              # relative to this file
    torque_Nm = 302.0                       # or the name of a torque slow signal
    bulk_temperature_C = 90.0
    speed_rpm = 1500.0                      # pinion speed

The contract is ``data_schemas/campaign.schema.json``. :func:`load_campaign` validates the
file once, at the boundary: a key or value the schema does not allow, a duplicate run id, a
gear set, DBC or mapping that cannot be found, or a non-finite number raises
:class:`CampaignError` naming the file, the key and its line. Run files are *not* required to
exist at load time: a missing recording is a failed run of the campaign (the observations stage
records it and goes on with the others), not a broken manifest.

Errors::

    RigtoolsError
    └── CampaignError (ValueError)     the manifest is malformed; names file, line and key
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from models.errors import ModelError
from models.geometry.gear_sets import GearSet, gear_set_path, load_gear_set, shipped_gear_sets
from rigtools.errors import CampaignError
from rigtools.schemas import iter_errors, load_schema

__all__ = [
    "CONDITION_KEYS",
    "SCHEMA",
    "AnalysisSettings",
    "Campaign",
    "CampaignError",
    "CampaignRun",
    "Sensors",
    "Thermal",
    "load_campaign",
]

SCHEMA = "campaign.schema.json"

#: Condition keys of a run, in table order.
CONDITION_KEYS = ("torque_Nm", "bulk_temperature_C", "oil_temperature_C", "speed_rpm")


# --------------------------------------------------------------------------------------------
# results


@dataclass(frozen=True)
class Sensors:
    """How the campaign's recordings map to channels.

    Attributes
    ----------
    dbc : pathlib.Path or None
        DBC for CAN logs (None: the reference layout).
    mapping : pathlib.Path or None
        Channel mapping file (``[sensors] map``).
    accel : tuple of str
        Accelerometer channels to analyse; empty: every uniform channel of each recording.
    speed : str or None
        Slow signal or tacho channel with the speed of ``speed_shaft`` (None: no Arms per step).
    speed_shaft : {'pinion', 'wheel'}
    pulses_per_rev : int or None
        Tacho pulses per revolution, when ``speed`` names a channel.
    """

    dbc: Path | None = None
    mapping: Path | None = None
    accel: tuple[str, ...] = ()
    speed: str | None = None
    speed_shaft: Literal["pinion", "wheel"] = "pinion"
    pulses_per_rev: int | None = None


@dataclass(frozen=True)
class Thermal:
    """The reference state the thermal closure is measured from (SEED-NOTES 8).

    Attributes
    ----------
    reference_temperature_C : float or None
        Temperature at which the backlash is stated (degC).
    housing : {'fixed-centre-distance', 'follows-oil'} or None
    line : int or None
        Line of the ``[thermal]`` header in the campaign file (None when absent).

    :func:`rigtools.campaign.thermal_state` turns it into the reference state of
    :mod:`models.thermal`.
    """

    reference_temperature_C: float | None = None
    housing: Literal["fixed-centre-distance", "follows-oil"] | None = None
    line: int | None = field(default=None, compare=False)


@dataclass(frozen=True)
class AnalysisSettings:
    """Settings of the observations stage (``[analysis]``; every key optional).

    Attributes
    ----------
    nperseg : int
        Welch window length (samples).
    prominence_dB : float
        Least prominence of a PSD peak (dB).
    f_range_Hz : tuple of float or None
        Band searched for peaks (Hz); None: the analysis default.
    max_peaks : int
        Most prominent peaks kept per channel.
    response : {'auto', 'displacement', 'velocity', 'acceleration'}
        SDOF response fitted to each peak; ``"auto"`` (default): the one the channel's unit
        names (:func:`rigtools.analysis.recording.response_for_unit`), and for a unit that
        names none, the best-fitting one, flagged ``response_guessed``.
    low_snr_dB : float
        Threshold of the ``low_snr`` flag (dB): a natural frequency whose peak prominence is
        below it, or a mesh harmonic this little above the order-spectrum floor.
    revs_per_block : int
        Revolutions per order-spectrum block (Arms).
    min_step_duration_s : float
        Shortest speed plateau taken as a step (s).
    step_rel_tolerance : float
        Relative half-width of a speed plateau.
    """

    nperseg: int = 4096
    prominence_dB: float = 6.0
    f_range_Hz: tuple[float, float] | None = None
    max_peaks: int = 20
    response: Literal["auto", "displacement", "velocity", "acceleration"] = "auto"
    low_snr_dB: float = 10.0
    revs_per_block: int = 8
    min_step_duration_s: float = 1.0
    step_rel_tolerance: float = 0.01


@dataclass(frozen=True)
class CampaignRun:
    """One recording of the campaign and its logged conditions.

    Conditions are a number in the unit their name carries, the name of a slow signal of the
    recording (its mean over the run is used), or None when not logged.

    Attributes
    ----------
    id : str
    file : pathlib.Path
        The recording, resolved against the campaign file's folder.
    file_as_written : str
    torque_Nm, bulk_temperature_C, oil_temperature_C, speed_rpm : float, str or None
        ``speed_rpm`` is the pinion speed.
    notes : str
    line : int or None
        Line of the run's ``[[run]]`` header in the campaign file.
    """

    id: str
    file: Path
    file_as_written: str
    torque_Nm: float | str | None = None
    bulk_temperature_C: float | str | None = None
    oil_temperature_C: float | str | None = None
    speed_rpm: float | str | None = None
    notes: str = ""
    line: int | None = None

    def conditions(self) -> dict[str, float | str | None]:
        """The four conditions by key."""
        return {k: getattr(self, k) for k in CONDITION_KEYS}

    def numeric_conditions(self) -> dict[str, float]:
        """The conditions given as numbers (for the run metadata of the recording)."""
        return {k: float(v) for k, v in self.conditions().items()
                if isinstance(v, int | float) and not isinstance(v, bool)}


@dataclass(frozen=True)
class Campaign:
    """A loaded, validated campaign.

    Attributes
    ----------
    name : str
    gear_set : str
        As written: a shipped name or a path.
    gear_set_path : str
        The gear-set file used.
    gear : models.geometry.GearSet
        The loaded gear set.
    sensors : Sensors
    thermal : Thermal
    analysis : AnalysisSettings
    runs : tuple of CampaignRun
    path : pathlib.Path
        The campaign file.
    description, rig : str
    calibration : dict or None
        The ``[calibration]`` block as written (schema-checked; resolved and checked in depth by
        :func:`rigtools.calibration.parse_calibration_block`), None when absent.
    key_lines : dict
        Line of every key of the file, by its path (``("calibration", "priors", "backlash")``);
        :meth:`line_of` looks keys up in it.
    """

    name: str
    gear_set: str
    gear_set_path: str
    gear: GearSet = field(compare=False, repr=False)
    sensors: Sensors
    thermal: Thermal
    analysis: AnalysisSettings
    runs: tuple[CampaignRun, ...]
    path: Path
    description: str = ""
    rig: str = ""
    calibration: dict[str, Any] | None = field(default=None, compare=False, repr=False)
    key_lines: dict[tuple[Any, ...], int] = field(default_factory=dict, compare=False,
                                                 repr=False)

    def line_of(self, dotted_key: str) -> int | None:
        """Line of a dotted key such as ``"calibration.priors.backlash.lower"``.

        The line of the nearest enclosing table written in the file when the key itself is
        not; None when neither is found.
        """
        p: tuple[Any, ...] = tuple(dotted_key.split("."))
        while p:
            if p in self.key_lines:
                return self.key_lines[p]
            p = p[:-1]
        return None

    @property
    def pinion_teeth(self) -> int:
        """Teeth of the pinion (z1)."""
        return int(self.gear.pair.pinion.teeth)

    @property
    def wheel_teeth(self) -> int:
        """Teeth of the wheel (z2)."""
        return int(self.gear.pair.wheel.teeth)

    def run(self, run_id: str) -> CampaignRun:
        """The run of that id."""
        for r in self.runs:
            if r.id == run_id:
                return r
        raise KeyError(run_id)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form of the resolved configuration (recorded with every output)."""

        def opt(p: Path | None) -> str | None:
            return None if p is None else str(p)

        s, t, a = self.sensors, self.thermal, self.analysis
        return {
            "path": str(self.path),
            "campaign": {"name": self.name, "description": self.description, "rig": self.rig,
                         "gear_set": self.gear_set, "gear_set_path": self.gear_set_path},
            "sensors": {"dbc": opt(s.dbc), "map": opt(s.mapping), "accel": list(s.accel),
                        "speed": s.speed, "speed_shaft": s.speed_shaft,
                        "pulses_per_rev": s.pulses_per_rev},
            "thermal": {"reference_temperature_C": t.reference_temperature_C,
                        "housing": t.housing},
            "analysis": {"nperseg": a.nperseg, "prominence_dB": a.prominence_dB,
                         "f_range_Hz": None if a.f_range_Hz is None else list(a.f_range_Hz),
                         "max_peaks": a.max_peaks, "response": a.response,
                         "low_snr_dB": a.low_snr_dB, "revs_per_block": a.revs_per_block,
                         "min_step_duration_s": a.min_step_duration_s,
                         "step_rel_tolerance": a.step_rel_tolerance},
            "run": [{"id": r.id, "file": str(r.file), "notes": r.notes, **r.conditions()}
                    for r in self.runs],
        }


# --------------------------------------------------------------------------------------------
# where keys are in the TOML text

_HEADER = re.compile(r"""^\s*(\[\[?)\s*([A-Za-z0-9_\-."' ]+?)\s*\]\]?\s*(#.*)?$""")
_KEY = re.compile(r"""^\s*("[^"]*"|'[^']*'|[A-Za-z0-9_\-]+(?:\s*\.\s*[A-Za-z0-9_\-]+)*)\s*=""")


def _unquote(part: str) -> str:
    part = part.strip()
    return part[1:-1] if len(part) >= 2 and part[0] == part[-1] and part[0] in "\"'" else part


class _Lines:
    """Line numbers of the tables, array-of-tables entries and keys of a TOML text.

    Paths are tuples as jsonschema reports them: ``("run", 2, "file")`` is the key ``file`` of
    the third ``[[run]]``. Good for the flat manifests rigtools reads (no multi-line strings
    holding ``key = value`` lines).
    """

    def __init__(self, text: str) -> None:
        self.lines: dict[tuple[Any, ...], int] = {}
        counts: dict[tuple[str, ...], int] = {}
        current: tuple[Any, ...] = ()
        for i, line in enumerate(text.splitlines(), 1):
            h = _HEADER.match(line)
            if h and not _KEY.match(line):
                names = tuple(_unquote(p) for p in h.group(2).split("."))
                if h.group(1) == "[[":
                    n = counts.get(names, 0)
                    counts[names] = n + 1
                    current = (*names, n)
                else:
                    current = names
                self.lines.setdefault(current, i)
                continue
            k = _KEY.match(line)
            if k:
                key = tuple(_unquote(p) for p in k.group(1).split("."))
                self.lines.setdefault((*current, *key), i)

    def line(self, path: tuple[Any, ...]) -> int | None:
        """Line of ``path``, or of its nearest enclosing table that is in the text."""
        p = tuple(path)
        while p:
            if p in self.lines:
                return self.lines[p]
            p = p[:-1]
        return None


_PATH_TOKEN = re.compile(r"\.([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]|\['((?:[^'\\]|\\.)*)'\]")


def _parse_json_path(json_path: str) -> tuple[Any, ...]:
    """``$.run[1].file`` -> ``("run", 1, "file")``."""
    out: list[Any] = []
    for m in _PATH_TOKEN.finditer(json_path.removeprefix("$")):
        if m.group(1) is not None:
            out.append(m.group(1))
        elif m.group(2) is not None:
            out.append(int(m.group(2)))
        else:
            out.append(m.group(3))
    return tuple(out)


def _dotted(path: tuple[Any, ...]) -> str:
    s = ""
    for p in path:
        s += f"[{p}]" if isinstance(p, int) else (f".{p}" if s else str(p))
    return s or "the top level"


def _table_name(path: tuple[Any, ...]) -> str:
    names = [p for p in path if not isinstance(p, int)]
    if not names:
        return "the top level"
    return f"[[{'.'.join(names)}]]" if path and isinstance(path[-1], int) else \
        f"[{'.'.join(names)}]"


# --------------------------------------------------------------------------------------------
# loading


def _walk_floats(obj: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[tuple[Any, ...], float]]:
    if isinstance(obj, float):
        yield path, obj
    elif isinstance(obj, dict):
        for k, v in obj.items():
            yield from _walk_floats(v, (*path, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _walk_floats(v, (*path, i))


def _schema_error(p: Path, lines: _Lines, json_path: str, message: str) -> CampaignError:
    path = _parse_json_path(json_path)
    unexpected = re.findall(r"'([^']+)'", message.split("(", 1)[1]) if (
        "were unexpected" in message or "was unexpected" in message) else []
    if unexpected:
        # name the first unknown key in file order, with its line
        keyed = sorted((lines.line((*path, k)) or 0, k) for k in unexpected)
        first_line, key = keyed[0]
        allowed = _allowed_keys(path)
        close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6) or [
            a for a in allowed if a.lower() == key.lower()]
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        more = f"; also unknown: {', '.join(k for _, k in keyed[1:])}" if len(keyed) > 1 else ""
        return CampaignError(
            p, f"line {first_line}" if first_line else None,
            f"one of the keys {', '.join(allowed)} in {_table_name(path)}"
            if allowed else "no such key",
            f"unknown key {key!r}{hint}{more}")
    line = lines.line(path)
    at = f"line {line}" if line else None
    m = re.match(r"'([^']+)' is a required property", message)
    if m:
        return CampaignError(p, at, f"key {m.group(1)!r} in {_table_name(path)}", "none")
    return CampaignError(p, at,
                         f"a value allowed by data_schemas/{SCHEMA} for {_dotted(path)}",
                         message)


def _allowed_keys(path: tuple[Any, ...]) -> list[str]:
    node: Any = load_schema(SCHEMA)
    for part in path:
        if isinstance(part, int):
            node = node.get("items", {})
        else:
            node = node.get("properties", {}).get(part, {})
    return list(node.get("properties", {}))


def _resolve(base: Path, value: str) -> Path:
    q = Path(value).expanduser()
    return q if q.is_absolute() else base / q


def load_campaign(path: str | Path) -> Campaign:
    """Read and validate a campaign manifest.

    Parameters
    ----------
    path : str or pathlib.Path
        The campaign TOML file.

    Returns
    -------
    Campaign

    Raises
    ------
    CampaignError
        Not TOML; a key or value ``data_schemas/campaign.schema.json`` does not allow (the
        message names the key and its line); a non-finite number; a duplicate run id; a gear
        set, DBC or mapping file that cannot be found or loaded.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CampaignError(p, None, "a campaign file", "no such file") from None
    except IsADirectoryError:
        raise CampaignError(p, None, "a campaign file", "a directory") from None
    except UnicodeDecodeError as exc:
        raise CampaignError(p, f"byte {exc.start}", "UTF-8 text", "undecodable bytes") from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        where = f"line {m.group(1)}, column {m.group(2)}" if m else None
        raise CampaignError(p, where, "a TOML file", None,
                            re.sub(r"\s*\(at line .*\)$", "", str(exc))) from exc
    lines = _Lines(text)
    errors = iter_errors(doc, SCHEMA)
    if errors:
        raise _schema_error(p, lines, *errors[0])
    for key_path, v in _walk_floats(doc):
        if not math.isfinite(v):
            line = lines.line(key_path)
            raise CampaignError(p, f"line {line}" if line else None,
                                f"a finite number for {_dotted(key_path)}", repr(v))

    def at(*where: Any) -> str | None:
        line = lines.line(tuple(where))
        return f"line {line}" if line else None

    base = p.parent
    camp = doc["campaign"]
    gear_set, gear_set_path, gear = _load_gear(p, base, camp["gear_set"], at("campaign",
                                                                             "gear_set"))
    sens = doc.get("sensors", {})
    files: dict[str, Path | None] = {}
    for key in ("dbc", "map"):
        if key in sens:
            f = _resolve(base, sens[key])
            if not f.is_file():
                raise CampaignError(p, at("sensors", key), f"sensors.{key} to name an existing "
                                    "file (relative to the campaign file)",
                                    f"{sens[key]!r}: no such file ({f})")
            files[key] = f
        else:
            files[key] = None
    if "pulses_per_rev" in sens and "speed" not in sens:
        raise CampaignError(p, at("sensors", "pulses_per_rev"),
                            "sensors.speed naming the tacho channel", "pulses_per_rev alone")
    sensors = Sensors(dbc=files["dbc"], mapping=files["map"],
                      accel=tuple(sens.get("accel", ())), speed=sens.get("speed"),
                      speed_shaft=sens.get("speed_shaft", "pinion"),
                      pulses_per_rev=sens.get("pulses_per_rev"))
    th = doc.get("thermal", {})
    thermal = Thermal(reference_temperature_C=_opt_float(th.get("reference_temperature_C")),
                      housing=th.get("housing"), line=lines.line(("thermal",)) if th else None)
    an = doc.get("analysis", {})
    f_range = an.get("f_range_Hz")
    if f_range is not None and not f_range[0] < f_range[1]:
        raise CampaignError(p, at("analysis", "f_range_Hz"), "f_range_Hz = [low, high] with "
                            "low < high (Hz)", repr(f_range))
    defaults = AnalysisSettings()
    analysis = AnalysisSettings(
        nperseg=int(an.get("nperseg", defaults.nperseg)),
        prominence_dB=float(an.get("prominence_dB", defaults.prominence_dB)),
        f_range_Hz=None if f_range is None else (float(f_range[0]), float(f_range[1])),
        max_peaks=int(an.get("max_peaks", defaults.max_peaks)),
        response=an.get("response", defaults.response),
        low_snr_dB=float(an.get("low_snr_dB", defaults.low_snr_dB)),
        revs_per_block=int(an.get("revs_per_block", defaults.revs_per_block)),
        min_step_duration_s=float(an.get("min_step_duration_s",
                                         defaults.min_step_duration_s)),
        step_rel_tolerance=float(an.get("step_rel_tolerance", defaults.step_rel_tolerance)),
    )
    runs = []
    seen: dict[str, int] = {}
    for i, r in enumerate(doc["run"]):
        if r["id"] in seen:
            raise CampaignError(p, at("run", i, "id"), "a unique run id",
                                f"{r['id']!r} again (first in run {seen[r['id']] + 1}, "
                                f"{at('run', seen[r['id']], 'id')})")
        seen[r["id"]] = i
        runs.append(CampaignRun(
            id=r["id"], file=_resolve(base, r["file"]), file_as_written=r["file"],
            **{k: _condition(r.get(k)) for k in CONDITION_KEYS},
            notes=r.get("notes", ""), line=lines.line(("run", i))))
    return Campaign(name=camp["name"], gear_set=gear_set, gear_set_path=gear_set_path,
                    gear=gear, sensors=sensors, thermal=thermal, analysis=analysis,
                    runs=tuple(runs), path=p, description=camp.get("description", ""),
                    rig=camp.get("rig", ""), calibration=doc.get("calibration"),
                    key_lines=dict(lines.lines))


def _opt_float(v: Any) -> float | None:
    return None if v is None else float(v)


def _condition(v: Any) -> float | str | None:
    if v is None or isinstance(v, str):
        return v
    return float(v)


def _load_gear(p: Path, base: Path, value: str, where: str | None
               ) -> tuple[str, str, GearSet]:
    looks_like_path = "/" in value or "\\" in value or value.endswith(".toml")
    try:
        if looks_like_path:
            f = _resolve(base, value)
            if not f.is_file():
                raise CampaignError(p, where, "campaign.gear_set to be a shipped gear set ("
                                    f"{', '.join(shipped_gear_sets())}) or a gear-set file",
                                    f"{value!r}: no such file ({f})")
        elif value in shipped_gear_sets():
            f = gear_set_path(value)
        else:
            f = _resolve(base, value)
            if not f.is_file():
                raise CampaignError(p, where, "campaign.gear_set to be a shipped gear set ("
                                    f"{', '.join(shipped_gear_sets())}) or a gear-set file",
                                    repr(value))
        return value, str(f), load_gear_set(f)
    except ModelError as exc:
        raise CampaignError(p, where, "a gear set that loads", None, str(exc)) from exc

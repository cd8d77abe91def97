"""Campaign manifests: the user's one description of an experiment (TOML).

A campaign names the gear set, says how recordings map to channels, fixes the thermal
reference state and the analysis settings, and lists one ``[[run]]`` per recording with its
conditions as the engineer logged them::

    [campaign]
    name = "FZG-C backlash study"
    gear_set = "fzg-c"                      # a shipped gear set, or a path to the user's own
    conditions = "runs.csv"                 # optional sheet of run conditions (see below)

    [sensors]                               # the campaign's default logger layout
    dbc = "rig.dbc"                         # CAN logs; MCAP needs no DBC
    map = "rig-map.toml"                    # channel mapping (optional)
    format = "blf"                          # force a reader (default: detected by content)
    accel = ["accel_1", "accel_2"]          # default: every uniform channel
    speed = "PinionSpeed_rpm"               # slow signal or tacho channel: enables Arms per step

    [thermal]
    reference_temperature_C = 20.0
    housing = "fixed-centre-distance"       # or "follows-oil"

    [analysis]                              # all optional
    nperseg = 4096

    [report]                                # all optional: the validation report
    title = "FZG-C backlash study, rig 2"
    f_n_rel_tolerance = 0.02                # |measured mesh mode - predicted| / predicted
    f_n_z_tolerance = 3.0                   # |measured - predicted| / predictive sd
    backlash_range_um = [5.0, 40.0]         # pass when the 90 % interval of c lies inside
    min_margin_um = 0.0                     # pass when q05 of the margin is at least this

    [[run]]
    id = "LS9-90C"
    file = "runs/ls9_90c.blf"               # relative to this file
    torque_Nm = 302.0                       # or the name of a torque slow signal
    bulk_temperature_C = 90.0
    speed_rpm = 1500.0                      # pinion speed

    [[run]]                                 # another logger: overrides of [sensors]
    id = "mcap-{stem}"                      # {stem}: the stem of each matching file
    file = "mcap/ls9_*.mcap"                # a glob: one run per matching file, sorted
    dbc = ""                                # "" drops the campaign's DBC / mapping
    map = ""
    format = "mcap"
    accel = ["imu/accel_x", "imu/accel_y"]

    [[run]]                                 # a run on another gear pair
    id = "KB-ramp-300"
    file = "runs/kb_ramp_300.mcap"
    gear_set = "kahraman-blankenship"       # shipped name or path; default [campaign] gear_set

Each ``[[run]]`` may override ``dbc``, ``map``, ``format`` and ``accel`` of ``[sensors]``
(:meth:`Campaign.sensors_for` gives a run's effective sensors), so recordings of several
loggers sit in one campaign. A ``[[run]] gear_set`` puts that run on another gear pair
(:meth:`Campaign.gear_for` gives a run's gear set): the observations stage uses its teeth and
pair for the run's mesh orders, and the natural-frequency calibration leaves such runs out
(they calibrate the SDOF run-up models, each on its own pair). A ``file`` holding ``*``, ``?``
or ``[`` is a glob (:mod:`rigtools.campaign.run_files`): one run per matching file, with the id
the ``[[run]]`` gives with ``{stem}`` replaced by the file's stem (``<id>-<stem>`` when it
holds none); a pattern that matches nothing is an error. ``[campaign] conditions`` names a CSV
sheet (:mod:`rigtools.campaign.conditions_sheet`) whose values fill the conditions a
``[[run]]`` does not give; a run and the sheet giving different values is an error naming both.

The contract is ``data_schemas/campaign.schema.json``. :func:`load_campaign` validates the
file once, at the boundary: a key or value the schema does not allow, a duplicate run id, a
gear set, DBC, mapping or conditions sheet that cannot be found, an unknown reader name, a
glob matching no file, or a non-finite number raises :class:`CampaignError` naming the file,
the key and its line (found by :mod:`rigtools.campaign.key_lines`; for the sheet: the CSV
file, its row and column). Run files are *not* required to exist at load time: a missing
recording is a failed run of the campaign (the observations stage records it and goes on
with the others), not a broken manifest.

Errors::

    RigtoolsError
    └── CampaignError (ValueError)     the manifest is malformed; names file, line and key
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any, Literal

from models.errors import ModelError
from models.geometry.gear_sets import GearSet, gear_set_path, load_gear_set, shipped_gear_sets
from rigtools.campaign.conditions_sheet import ConditionsSheet, read_conditions_sheet
from rigtools.campaign.key_lines import KeyLines, dotted, schema_error
from rigtools.campaign.run_files import expand_run_files, is_glob, run_id_for
from rigtools.errors import CampaignError
from rigtools.ingest.registry import READERS
from rigtools.schemas import iter_errors

__all__ = [
    "CONDITION_KEYS",
    "SCHEMA",
    "SENSOR_OVERRIDES",
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

#: Keys of ``[sensors]`` a ``[[run]]`` may override.
SENSOR_OVERRIDES = ("dbc", "map", "format", "accel")


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
    format : str or None
        Reader forced instead of detecting it by content (a name of
        :data:`rigtools.ingest.registry.READERS`); None: detected.
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
    format: str | None = None


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
    max_mesh_order : int
        Highest mesh harmonic whose peaks (with shaft sidebands) are classed as mesh lines
        rather than modes (:func:`rigtools.analysis.peaks.analyse_peaks`).
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
    max_mesh_order: int = 5
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
    dbc, mapping : pathlib.Path or None
        The run's own DBC and mapping (``dbc``, ``map``), when it overrides them (None with
        the key in ``overrides``: the campaign's is dropped).
    format : str or None
        The run's forced reader, when it overrides it.
    accel : tuple of str
        The run's accelerometer channels, when it overrides them.
    overrides : tuple of str
        The keys of ``[sensors]`` the run overrides (of :data:`SENSOR_OVERRIDES`);
        :meth:`Campaign.sensors_for` applies them.
    pattern : str or None
        The glob the run's file was matched by (as written), None for a plain file.
    gear_set : str or None
        The run's own gear set as written (``[[run]] gear_set``: a shipped name or a path),
        None when it runs on the campaign's.
    gear_set_path : str or None
        The gear-set file of ``gear_set``, None with it.
    gear : models.geometry.GearSet or None
        The loaded gear set of ``gear_set``, None with it (:meth:`Campaign.gear_for`).
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
    dbc: Path | None = None
    mapping: Path | None = None
    format: str | None = None
    accel: tuple[str, ...] = ()
    overrides: tuple[str, ...] = ()
    pattern: str | None = None
    gear_set: str | None = None
    gear_set_path: str | None = None
    gear: GearSet | None = field(default=None, compare=False, repr=False)

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
    report : dict or None
        The ``[report]`` block as written (schema-checked, ``backlash_range_um`` increasing),
        None when absent; read by :mod:`rigtools.report`.
    conditions_sheet : pathlib.Path or None
        The CSV sheet of conditions (``[campaign] conditions``), resolved; its values are
        already in the runs.
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
    report: dict[str, Any] | None = field(default=None, compare=False, repr=False)
    conditions_sheet: Path | None = None

    def sensors_for(self, run: CampaignRun) -> Sensors:
        """The sensors a run is read and analysed with: ``[sensors]`` and the run's overrides.

        Parameters
        ----------
        run : CampaignRun

        Returns
        -------
        Sensors
            ``[sensors]`` with the run's ``dbc``, ``map``, ``format`` and ``accel`` in place of
            the campaign's, for the keys the run sets.
        """
        o = run.overrides
        s = self.sensors
        if not o:
            return s
        return replace(s, dbc=run.dbc if "dbc" in o else s.dbc,
                       mapping=run.mapping if "map" in o else s.mapping,
                       format=run.format if "format" in o else s.format,
                       accel=run.accel if "accel" in o else s.accel)

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

    def gear_for(self, run_id: str) -> GearSet:
        """The gear set a run was run on: its ``[[run]] gear_set``, else the campaign's.

        Parameters
        ----------
        run_id : str

        Returns
        -------
        models.geometry.GearSet

        Raises
        ------
        KeyError
            No run of that id.
        """
        r = self.run(run_id)
        return self.gear if r.gear is None else r.gear

    def gear_set_for(self, run_id: str) -> str:
        """The gear set of a run as written (its ``[[run]] gear_set``, else the campaign's)."""
        r = self.run(run_id)
        return self.gear_set if r.gear_set is None else r.gear_set

    def on_campaign_gear(self, run_id: str) -> bool:
        """Whether a run is on the campaign's gear set (no ``gear_set``, or the same file)."""
        r = self.run(run_id)
        return r.gear_set_path is None or Path(r.gear_set_path) == Path(self.gear_set_path)

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

        def overrides(r: CampaignRun) -> dict[str, Any]:
            values = {"dbc": opt(r.dbc), "map": opt(r.mapping), "format": r.format,
                      "accel": list(r.accel)}
            return {k: values[k] for k in r.overrides}

        s, t, a = self.sensors, self.thermal, self.analysis
        return {
            "path": str(self.path),
            "campaign": {"name": self.name, "description": self.description, "rig": self.rig,
                         "gear_set": self.gear_set, "gear_set_path": self.gear_set_path,
                         "conditions": opt(self.conditions_sheet)},
            "sensors": {"dbc": opt(s.dbc), "map": opt(s.mapping), "format": s.format,
                        "accel": list(s.accel), "speed": s.speed, "speed_shaft": s.speed_shaft,
                        "pulses_per_rev": s.pulses_per_rev},
            "thermal": {"reference_temperature_C": t.reference_temperature_C,
                        "housing": t.housing},
            "analysis": {"nperseg": a.nperseg, "prominence_dB": a.prominence_dB,
                         "f_range_Hz": None if a.f_range_Hz is None else list(a.f_range_Hz),
                         "max_peaks": a.max_peaks, "max_mesh_order": a.max_mesh_order,
                         "response": a.response,
                         "low_snr_dB": a.low_snr_dB, "revs_per_block": a.revs_per_block,
                         "min_step_duration_s": a.min_step_duration_s,
                         "step_rel_tolerance": a.step_rel_tolerance},
            "report": None if self.report is None else dict(self.report),
            "run": [{"id": r.id, "file": str(r.file), "notes": r.notes, **r.conditions(),
                     "file_as_written": r.file_as_written, "pattern": r.pattern,
                     "sensors": overrides(r),
                     **({} if r.gear_set is None else {"gear_set": r.gear_set,
                                                       "gear_set_path": r.gear_set_path})}
                    for r in self.runs],
        }


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
    lines = KeyLines(text)
    errors = iter_errors(doc, SCHEMA)
    if errors:
        raise schema_error(p, lines, *errors[0], SCHEMA)
    for key_path, v in _walk_floats(doc):
        if not math.isfinite(v):
            line = lines.line(key_path)
            raise CampaignError(p, f"line {line}" if line else None,
                                f"a finite number for {dotted(key_path)}", repr(v))

    def at(*where: Any) -> str | None:
        line = lines.line(tuple(where))
        return f"line {line}" if line else None

    base = p.parent
    camp = doc["campaign"]
    gear_set, gear_set_path, gear = _load_gear(p, base, camp["gear_set"], at("campaign",
                                                                             "gear_set"))
    gears: dict[str, tuple[str, GearSet]] = {}  # run gear sets loaded, by value as written
    sens = doc.get("sensors", {})
    files: dict[str, Path | None] = {}
    for key in ("dbc", "map"):
        files[key] = (_sensor_file(p, base, sens[key], f"sensors.{key}", at("sensors", key))
                      if key in sens else None)
    if "format" in sens:
        _check_format(p, sens["format"], "sensors.format", at("sensors", "format"))
    if "pulses_per_rev" in sens and "speed" not in sens:
        raise CampaignError(p, at("sensors", "pulses_per_rev"),
                            "sensors.speed naming the tacho channel", "pulses_per_rev alone")
    sensors = Sensors(dbc=files["dbc"], mapping=files["map"],
                      accel=tuple(sens.get("accel", ())), speed=sens.get("speed"),
                      speed_shaft=sens.get("speed_shaft", "pinion"),
                      pulses_per_rev=sens.get("pulses_per_rev"), format=sens.get("format"))
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
        max_mesh_order=int(an.get("max_mesh_order", defaults.max_mesh_order)),
        response=an.get("response", defaults.response),
        low_snr_dB=float(an.get("low_snr_dB", defaults.low_snr_dB)),
        revs_per_block=int(an.get("revs_per_block", defaults.revs_per_block)),
        min_step_duration_s=float(an.get("min_step_duration_s",
                                         defaults.min_step_duration_s)),
        step_rel_tolerance=float(an.get("step_rel_tolerance", defaults.step_rel_tolerance)),
    )
    report = doc.get("report")
    if report is not None and "backlash_range_um" in report:
        lo, hi = report["backlash_range_um"]
        if not lo < hi:
            raise CampaignError(p, at("report", "backlash_range_um"), "backlash_range_um = "
                                "[lo, hi] with lo < hi (um)", repr(report["backlash_range_um"]))
    runs: list[CampaignRun] = []
    origin: list[int] = []  # index of the [[run]] each run comes from
    seen: dict[str, tuple[int, str | None]] = {}  # run id -> ([[run]] index, glob match)
    for i, r in enumerate(doc["run"]):
        sensors_of_run = _run_sensors(p, base, r, partial(at, "run", i))
        if "gear_set" in r:
            if r["gear_set"] not in gears:
                _, path_i, gear_i = _load_gear(p, base, r["gear_set"], at("run", i, "gear_set"),
                                               key="run.gear_set")
                gears[r["gear_set"]] = (path_i, gear_i)
            sensors_of_run.update(gear_set=r["gear_set"], gear_set_path=gears[r["gear_set"]][0],
                                  gear=gears[r["gear_set"]][1])
        for file, run_id, pattern in _run_files(p, base, r, at("run", i, "file")):
            if run_id in seen:
                j, first_file = seen[run_id]
                this = f" (from {file!r})" if pattern is not None else ""
                first = f" from {first_file!r}" if first_file is not None else ""
                raise CampaignError(p, at("run", i, "id"), "a unique run id",
                                    f"{run_id!r}{this} again (first in run {j + 1}{first}, "
                                    f"{at('run', j, 'id')})")
            seen[run_id] = (i, file if pattern is not None else None)
            origin.append(i)
            runs.append(CampaignRun(
                id=run_id, file=_resolve(base, file), file_as_written=file,
                torque_Nm=_condition(r.get("torque_Nm")),
                bulk_temperature_C=_condition(r.get("bulk_temperature_C")),
                oil_temperature_C=_condition(r.get("oil_temperature_C")),
                speed_rpm=_condition(r.get("speed_rpm")),
                notes=r.get("notes", ""), line=lines.line(("run", i)), pattern=pattern,
                **sensors_of_run))
    sheet_path: Path | None = None
    if "conditions" in camp:
        sheet_path = _resolve(base, camp["conditions"])
        if not sheet_path.is_file():
            raise CampaignError(p, at("campaign", "conditions"), "campaign.conditions to name "
                                "an existing CSV file (relative to the campaign file)",
                                f"{camp['conditions']!r}: no such file ({sheet_path})")
        sheet = read_conditions_sheet(sheet_path, CONDITION_KEYS)
        runs = _apply_sheet(p, sheet, runs, [doc["run"][i] for i in origin], origin, at)
    return Campaign(name=camp["name"], gear_set=gear_set, gear_set_path=gear_set_path,
                    gear=gear, sensors=sensors, thermal=thermal, analysis=analysis,
                    runs=tuple(runs), path=p, description=camp.get("description", ""),
                    rig=camp.get("rig", ""), calibration=doc.get("calibration"),
                    key_lines=dict(lines.lines), report=report, conditions_sheet=sheet_path)


def _sensor_file(p: Path, base: Path, value: str, key: str, where: str | None) -> Path:
    f = _resolve(base, value)
    if not f.is_file():
        raise CampaignError(p, where, f"{key} to name an existing file (relative to the "
                            "campaign file)", f"{value!r}: no such file ({f})")
    return f


def _check_format(p: Path, value: str, key: str, where: str | None) -> None:
    if value not in READERS:
        close = difflib.get_close_matches(value.lower(), list(READERS), n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise CampaignError(p, where, f"{key} to be one of {', '.join(READERS)}",
                            f"{value!r}{hint}")


def _run_files(p: Path, base: Path, r: dict[str, Any], where: str | None
               ) -> list[tuple[str, str, str | None]]:
    """The files of a ``[[run]]``: (file as shown, run id, the glob or None) per run.

    A plain file is shown as written; a glob's match relative to the campaign's folder
    (absolute when the glob is).
    """
    file = r["file"]
    if not is_glob(file) or _resolve(base, file).is_file():  # a file whose name holds "[" is one
        return [(file, r["id"], None)]
    matches = expand_run_files(base, file)
    if not matches:
        raise CampaignError(p, where, "the glob in run.file to match at least one file "
                            "(relative to the campaign file)", f"{file!r}: no match in {base}")
    out = []
    for m in matches:
        shown = m.relative_to(base) if m.is_relative_to(base) else m
        out.append((shown.as_posix(), run_id_for(r["id"], m), file))
    return out


def _run_sensors(p: Path, base: Path, r: dict[str, Any], at: Callable[[str], str | None]
                 ) -> dict[str, Any]:
    """The ``[sensors]`` overrides of a ``[[run]]`` as :class:`CampaignRun` fields."""
    out: dict[str, Any] = {}
    for key, name in (("dbc", "dbc"), ("map", "mapping")):
        if key in r:
            out[name] = (None if r[key] == "" else
                         _sensor_file(p, base, r[key], f"run.{key}", at(key)))
    if "format" in r:
        _check_format(p, r["format"], "run.format", at("format"))
        out["format"] = r["format"]
    if "accel" in r:
        out["accel"] = tuple(r["accel"])
    out["overrides"] = tuple(k for k in SENSOR_OVERRIDES if k in r)
    return out


def _apply_sheet(p: Path, sheet: ConditionsSheet, runs: list[CampaignRun],
                 tables: list[dict[str, Any]], origin: list[int],
                 at: Callable[..., str | None]
                 ) -> list[CampaignRun]:
    """The runs with the sheet's values where their ``[[run]]`` gives none.

    A run giving a value and the sheet another is an error naming both; a sheet row naming no
    run of the campaign is an error naming its row; a run the sheet does not name is kept as
    it is.
    """
    by_id = {r.id: r for r in runs}
    for sheet_row in sheet.rows.values():
        if sheet_row.run_id not in by_id:
            close = difflib.get_close_matches(sheet_row.run_id, list(by_id), n=1, cutoff=0.6)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise CampaignError(sheet.path, f"row {sheet_row.row}, column 'run_id'",
                                f"a run id of the campaign {p}",
                                f"{sheet_row.run_id!r}{hint}, not a run of it")
    out = []
    for run, table, i in zip(runs, tables, origin, strict=True):
        row = sheet.rows.get(run.id)
        if row is None:
            out.append(run)
            continue
        changes: dict[str, Any] = {}
        for key, value in row.values.items():
            if key not in table:
                changes[key] = value
                continue
            given = table[key]
            same = (given == value if isinstance(given, str) or isinstance(value, str)
                    else float(given) == float(value))
            if not same:
                raise CampaignError(p, at("run", i, key), f"one value of {key} for run {run.id!r}",
                                    f"{given!r} here and {value!r} in {sheet.path} at row "
                                    f"{row.row}, column {key!r}")
        out.append(replace(run, **changes) if changes else run)
    return out


def _opt_float(v: Any) -> float | None:
    return None if v is None else float(v)


def _condition(v: Any) -> float | str | None:
    if v is None or isinstance(v, str):
        return v
    return float(v)


def _load_gear(p: Path, base: Path, value: str, where: str | None,
               key: str = "campaign.gear_set") -> tuple[str, str, GearSet]:
    looks_like_path = "/" in value or "\\" in value or value.endswith(".toml")
    try:
        if looks_like_path:
            f = _resolve(base, value)
            if not f.is_file():
                raise CampaignError(p, where, f"{key} to be a shipped gear set ("
                                    f"{', '.join(shipped_gear_sets())}) or a gear-set file",
                                    f"{value!r}: no such file ({f})")
        elif value in shipped_gear_sets():
            f = gear_set_path(value)
        else:
            f = _resolve(base, value)
            if not f.is_file():
                raise CampaignError(p, where, f"{key} to be a shipped gear set ("
                                    f"{', '.join(shipped_gear_sets())}) or a gear-set file",
                                    repr(value))
        return value, str(f), load_gear_set(f)
    except ModelError as exc:
        raise CampaignError(p, where, "a gear set that loads", None,
                            f"{key} = {value!r}: {exc}") from exc

"""Gear sets as data files: the shipped ones (``models/gear_sets/*.toml``) and the user's own.

The file format (mm and degrees at this edge, the unit in every key) is described by
``data_schemas/gear_set.schema.json``; this loader checks keys and types itself (``models``
has no dependency on the schema machinery of ``rigtools``) and the test suite validates every
shipped file against the schema as well.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from models.errors import GeometryError
from models.geometry.gear_pair import Gear, GearPair, Material

__all__ = ["GearSet", "gear_set_path", "load_gear_set", "shipped_gear_sets"]

_DIR = Path(__file__).resolve().parent.parent / "gear_sets"

_TOP = {"gear_set", "pinion", "wheel", "material"}
_SET = {"name", "source", "module_mm", "pressure_angle_deg", "face_width_mm",
        "centre_distance_mm", "backlash_line_of_action_mm"}
_GEAR = {"teeth", "profile_shift", "tip_diameter_mm", "root_diameter_mm", "bore_diameter_mm",
         "addendum_coeff", "dedendum_coeff", "root_fillet_coeff", "material"}
_MATERIAL = {"youngs_modulus_MPa": ("youngs_modulus_Pa", 1e6),
             "poisson_ratio": ("poisson_ratio", 1.0),
             "density_kg_m3": ("density_kg_m3", 1.0),
             "thermal_expansion_per_K": ("thermal_expansion_per_K", 1.0),
             "specific_heat_J_kgK": ("specific_heat_J_kgK", 1.0),
             "conductivity_W_mK": ("conductivity_W_mK", 1.0)}


@dataclass(frozen=True)
class GearSet:
    """A named gear pair with the extras a data file may carry.

    Attributes
    ----------
    name : str
    pair : GearPair
    source : str
        Where the numbers come from.
    backlash_line_of_action_m : float or None
        Stated backlash on the line of action (m), when the source gives one.
    path : str
    """

    name: str
    pair: GearPair
    source: str = ""
    backlash_line_of_action_m: float | None = None
    path: str = ""


def shipped_gear_sets() -> list[str]:
    """Names of the gear sets shipped with rigtools."""
    return sorted(p.stem for p in _DIR.glob("*.toml"))


def gear_set_path(name: str) -> Path:
    """Path of a shipped gear set by name."""
    p = _DIR / f"{name}.toml"
    if not p.is_file():
        raise GeometryError("gear_set", name, f"no shipped gear set of that name; shipped: "
                            f"{', '.join(shipped_gear_sets())}")
    return p


def _unknown(where: str, keys: set[str], allowed: set[str]) -> None:
    extra = sorted(keys - allowed)
    if extra:
        raise GeometryError(f"{where}.{extra[0]}", None,
                            f"unknown key; allowed: {', '.join(sorted(allowed))}")


def _number(where: str, d: dict[str, Any], key: str, default: float | None = None) -> Any:
    if key not in d:
        if default is None:
            raise GeometryError(f"{where}.{key}", None, "required")
        return default
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise GeometryError(f"{where}.{key}", v, "must be a finite number")
    return float(v)


def _material(where: str, d: dict[str, Any], base: Material | None) -> Material:
    _unknown(where, set(d), set(_MATERIAL))
    kwargs = {}
    for key, (attr, factor) in _MATERIAL.items():
        if key in d:
            kwargs[attr] = _number(where, d, key) * factor
        elif base is not None:
            kwargs[attr] = getattr(base, attr)
    return Material(**kwargs)


def _gear(where: str, d: dict[str, Any], material: Material) -> Gear:
    _unknown(where, set(d), _GEAR)
    teeth = d.get("teeth")
    if isinstance(teeth, bool) or not isinstance(teeth, int):
        raise GeometryError(f"{where}.teeth", teeth, "must be an integer")
    mm = 1e-3
    opt = {k: _number(where, d, k) * mm for k in ("tip_diameter_mm", "root_diameter_mm",
                                                   "bore_diameter_mm") if k in d}
    return Gear(
        teeth=teeth,
        profile_shift=_number(where, d, "profile_shift", 0.0),
        tip_diameter_m=opt.get("tip_diameter_mm"),
        root_diameter_m=opt.get("root_diameter_mm"),
        addendum_coeff=_number(where, d, "addendum_coeff", 1.0),
        dedendum_coeff=_number(where, d, "dedendum_coeff", 1.25),
        root_fillet_coeff=_number(where, d, "root_fillet_coeff", 0.38),
        material=_material(f"{where}.material", d.get("material", {}), material),
        bore_diameter_m=opt.get("bore_diameter_mm"),
    )


def load_gear_set(name_or_path: str | Path) -> GearSet:
    """Load a gear set: a shipped name (``"fzg-c"``) or a TOML file of the user's.

    Raises
    ------
    GeometryError
        Unknown or missing keys, non-numbers, or geometry that cannot mesh; the message names
        the key (``pinion.profile_shift``) and, for files, the file.
    """
    p = Path(name_or_path)
    if not p.suffix and not p.exists():
        p = gear_set_path(str(name_or_path))
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise GeometryError("gear_set", str(p), "no such file") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise GeometryError("gear_set", str(p), f"not a TOML file: {exc}") from exc
    try:
        _unknown("", set(doc), _TOP)
        gs = doc.get("gear_set", {})
        _unknown("gear_set", set(gs), _SET)
        material = _material("material", doc.get("material", {}), None)
        deg, mm = math.pi / 180, 1e-3
        centre = gs.get("centre_distance_mm")
        pair = GearPair(
            pinion=_gear("pinion", doc.get("pinion", {}), material),
            wheel=_gear("wheel", doc.get("wheel", {}), material),
            module_m=_number("gear_set", gs, "module_mm") * mm,
            pressure_angle_rad=_number("gear_set", gs, "pressure_angle_deg") * deg,
            face_width_m=_number("gear_set", gs, "face_width_mm") * mm,
            centre_distance_m=None if centre is None else
            _number("gear_set", gs, "centre_distance_mm") * mm,
            name=str(gs.get("name", p.stem)),
        )
        backlash = gs.get("backlash_line_of_action_mm")
        return GearSet(
            name=pair.name,
            pair=pair,
            source=str(gs.get("source", "")),
            backlash_line_of_action_m=None if backlash is None else
            _number("gear_set", gs, "backlash_line_of_action_mm") * mm,
            path=str(p),
        )
    except GeometryError as exc:
        raise GeometryError(f"{p.name}: {exc.parameter}", exc.value, exc.reason) from None

r"""What every table of the ``[calibration]`` block is checked with.

:class:`BlockParser` checks one value at a time (a number, an integer, a choice, a pair, a
list of names, a prior table) and raises :class:`rigtools.errors.CampaignError` naming the
key and its line in the campaign file. A parameter table (name -> :class:`ParameterInfo`)
with its ``priors`` and ``fixed`` sub-tables resolves to :class:`ParameterSpec` s through
:func:`parameter_specs`; :func:`default_parameter_specs` gives the table's defaults. The
natural-frequency calibration (:mod:`rigtools.calibration.config`) and the run-up calibration
(:mod:`rigtools.calibration.runup_config`) share them.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rigtools.calibration.priors import DISTRIBUTIONS, Prior, prior_from_mapping
from rigtools.errors import CampaignError

__all__ = [
    "BlockParser",
    "ParameterInfo",
    "ParameterSpec",
    "ValueCheck",
    "default_parameter_specs",
    "parameter_specs",
    "spec_named",
    "spec_tables",
]


@dataclass(frozen=True)
class ParameterInfo:
    """What a calibration parameter is.

    Attributes
    ----------
    unit : str
        Unit of its values in priors, fixed values and the summary.
    domain : (float, float)
        Values the physics accepts (a prior is cut to it, a fixed value must lie in it).
    default : Prior or float
        Default prior, or the default fixed value.
    description : str
    """

    unit: str
    domain: tuple[float, float]
    default: Prior | float
    description: str


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter as configured: a prior (sampled) or a fixed value.

    Attributes
    ----------
    name : str
    unit : str
    prior : Prior or None
        None when fixed.
    fixed : float or None
        The fixed value, in ``unit``.
    """

    name: str
    unit: str
    prior: Prior | None
    fixed: float | None

    @property
    def free(self) -> bool:
        """Sampled (has a prior and no fixed value)."""
        return self.fixed is None


#: ``check(parser, key, value)``: the value normalised, or a :class:`CampaignError`.
ValueCheck = Callable[["BlockParser", str, Any], Any]


class BlockParser:
    """Checks one block, raising :class:`CampaignError` with the key and its line.

    Every check takes the dotted ``key`` of the value (``"calibration.runup.walkers"``), names
    it in its message and returns the value normalised.

    Parameters
    ----------
    source : str
        The campaign file, for the messages.
    line_of : callable
        ``line_of(key)`` -> the line of ``key`` (or of its nearest enclosing table) in the
        file, or None when unknown.
    """

    def __init__(self, source: str, line_of: Callable[[str], int | None]) -> None:
        self.source = source
        self.line_of = line_of

    def error(self, key: str, expected: str, found: str) -> CampaignError:
        """The error for ``key``: ``expected`` was wanted, ``found`` was given."""
        line = self.line_of(key)
        return CampaignError(self.source, f"line {line}" if line else None, expected, found)

    def unknown(self, key: str, name: str, allowed: Sequence[str], what: str) -> CampaignError:
        """The error for an unknown ``name`` at ``key`` (``what``: the names ``allowed``)."""
        close = difflib.get_close_matches(name, list(allowed), n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        return self.error(key, f"{what}: {', '.join(allowed)}", f"unknown {name!r}{hint}")

    def table(self, key: str, value: Any) -> Mapping[str, Any]:
        """``value`` as a table."""
        if not isinstance(value, Mapping):
            raise self.error(key, f"a table for {key}", repr(value))
        return value

    def known_table(self, key: str, value: Any, allowed: Sequence[str]) -> Mapping[str, Any]:
        """``value`` as the table ``[key]`` whose keys are all among ``allowed``."""
        t = self.table(key, value)
        for k in t:
            if k not in allowed:
                raise self.unknown(f"{key}.{k}", k, allowed, f"a key of [{key}]")
        return t

    def values(self, key: str, t: Mapping[str, Any],
               checks: Mapping[str, ValueCheck]) -> dict[str, Any]:
        """The keys of table ``[key]`` that ``checks`` names, each checked, in its order.

        ``checks[name](parser, dotted_key, value)`` returns the value normalised (or raises).
        """
        return {k: check(self, f"{key}.{k}", t[k]) for k, check in checks.items() if k in t}

    def number(self, key: str, value: Any, *, minimum: float | None = None,
               exclusive: bool = False, maximum: float | None = None,
               exclusive_max: bool = False) -> float:
        """A finite number within the bounds given (``exclusive``: the bound excluded)."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, f"a number for {key}", repr(value))
        v = float(value)
        if not math.isfinite(v):
            raise self.error(key, f"a finite number for {key}", repr(value))
        if minimum is not None and (v <= minimum if exclusive else v < minimum):
            raise self.error(key, f"{key} {'>' if exclusive else '>='} {minimum:g}", f"{v:g}")
        if maximum is not None and (v >= maximum if exclusive_max else v > maximum):
            raise self.error(key, f"{key} {'<' if exclusive_max else '<='} {maximum:g}",
                             f"{v:g}")
        return v

    def integer(self, key: str, value: Any, *, minimum: int) -> int:
        """An integer, at least ``minimum``."""
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"an integer for {key}", repr(value))
        if value < minimum:
            raise self.error(key, f"{key} >= {minimum}", str(value))
        return int(value)

    def boolean(self, key: str, value: Any) -> bool:
        """``true`` or ``false``."""
        if not isinstance(value, bool):
            raise self.error(key, f"true or false for {key}", repr(value))
        return value

    def walkers(self, key: str, value: Any) -> int:
        """An even number of walkers, at least 4."""
        w = self.integer(key, value, minimum=4)
        if w % 2:
            raise self.error(key, "an even number of walkers", str(w))
        return w

    def choice(self, key: str, value: Any, allowed: Sequence[str]) -> str:
        """One of the strings ``allowed``."""
        if not isinstance(value, str) or value not in allowed:
            raise self.error(key, f"one of {', '.join(repr(a) for a in allowed)} for {key}",
                             repr(value))
        return value

    def pair(self, key: str, value: Any, *, positive: bool = True) -> tuple[float, float]:
        """``[low, high]`` with ``low < high``, both above 0 (``positive``) or at least 0."""
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise self.error(key, f"two numbers [low, high] for {key}", repr(value))
        lo, hi = (self.number(key, v, minimum=0.0, exclusive=positive) for v in value)
        if not lo < hi:
            raise self.error(key, f"{key} = [low, high] with low < high", repr(list(value)))
        return lo, hi

    def strings(self, key: str, value: Any) -> tuple[str, ...]:
        """A list of non-empty names without repeats."""
        if not isinstance(value, list | tuple) or not all(
                isinstance(v, str) and v for v in value):
            raise self.error(key, f"a list of names for {key}", repr(value))
        if len(set(value)) != len(value):
            raise self.error(key, f"names without repeats for {key}", repr(list(value)))
        return tuple(value)

    def choices(self, key: str, value: Any, allowed: Sequence[str]) -> tuple[str, ...]:
        """A list of names without repeats, each one of ``allowed``."""
        names = self.strings(key, value)
        for n in names:
            self.choice(key, n, allowed)
        return names

    # -- priors ---------------------------------------------------------------------------
    def prior(self, name: str, spec: Any, *, where: str,
              table: Mapping[str, ParameterInfo]) -> Prior:
        """The prior table ``[where.name]`` of ``table``'s parameter ``name``, cut to its domain."""
        key = f"{where}.{name}"
        spec = self.table(key, spec)
        if "dist" not in spec:
            raise self.error(key, f"key 'dist' ({', '.join(DISTRIBUTIONS)}) in {key}", "none")
        dist = self.choice(f"{key}.dist", spec["dist"], list(DISTRIBUTIONS))
        required, optional = DISTRIBUTIONS[dist]
        for k in spec:
            if k != "dist" and k not in required + optional:
                raise self.unknown(f"{key}.{k}", k, ("dist", *required, *optional),
                                   f"a key of a {dist} prior in {key}")
        for k in required:
            if k not in spec:
                raise self.error(key, f"key {k!r} of a {dist} prior in {key}", "none")
        values = {k: self.number(f"{key}.{k}", spec[k]) for k in spec if k != "dist"}
        for k in ("sd", "sigma", "median"):
            if k in values and not values[k] > 0:
                raise self.error(f"{key}.{k}", f"{k} > 0 in {key}", f"{k} = {values[k]:g}")
        if "lower" in values and "upper" in values and not values["lower"] < values["upper"]:
            raise self.error(f"{key}.lower", f"lower < upper in {key}",
                             f"lower = {values['lower']:g}, upper = {values['upper']:g}")
        lo_dom, hi_dom = table[name].domain
        natural_lo = {"lognormal": 0.0, "halfnormal": 0.0}.get(dist, -math.inf)
        lo = max(values.get("lower", natural_lo), lo_dom, natural_lo)
        hi = min(values.get("upper", math.inf), hi_dom)
        if not lo < hi:
            raise self.error(key, f"a prior for {name} that admits values in its domain "
                             f"[{lo_dom:g}, {hi_dom:g}] {table[name].unit}",
                             f"support [{values.get('lower', natural_lo):g}, "
                             f"{values.get('upper', math.inf):g}]")
        if "lower" in values and dist == "lognormal" and values["lower"] < 0:
            raise self.error(f"{key}.lower", f"lower >= 0 for a lognormal prior in {key}",
                             f"lower = {values['lower']:g}")
        built = dict(values, dist=dist)
        if (lo, hi) != (values.get("lower", natural_lo), values.get("upper", math.inf)):
            built.update(lower=lo, upper=hi)
            if dist == "uniform" and not math.isfinite(hi):
                raise self.error(key, f"finite bounds for {name}", f"[{lo:g}, {hi:g}]")
            if dist == "halfnormal":
                built.pop("lower", None)
        try:
            return prior_from_mapping(built)
        except ValueError as exc:  # every case is checked above; kept as a safety net
            raise self.error(key, f"a valid prior for {name}", str(exc)) from None


def parameter_specs(p: BlockParser, priors: Any, fixed: Any, *,
                    table: Mapping[str, ParameterInfo], where: str,
                    check: Callable[[str, Prior | None], None] | None = None,
                    ) -> tuple[ParameterSpec, ...]:
    """``[<where>.priors]`` and ``[<where>.fixed]`` resolved over ``table``, in its order.

    Parameters
    ----------
    p : BlockParser
    priors, fixed : mapping or None
        The two sub-tables as parsed (None: not given).
    table : mapping
        Parameter name -> :class:`ParameterInfo`; a parameter given neither a prior nor a
        fixed value keeps its default.
    where : str
        The dotted key of the enclosing table (``"calibration"``, ``"calibration.runup"``).
    check : callable, optional
        ``check(name, prior)`` may refuse a prior the caller cannot use (a
        :class:`CampaignError`).

    Returns
    -------
    tuple of ParameterSpec
    """
    pwhere, fwhere = f"{where}.priors", f"{where}.fixed"
    priors = {} if priors is None else p.table(pwhere, priors)
    fixed = {} if fixed is None else p.table(fwhere, fixed)
    names = list(table)
    for given, at in ((priors, pwhere), (fixed, fwhere)):
        for n in given:
            if n not in table:
                raise p.unknown(f"{at}.{n}", n, names, f"a parameter name in [{at}]")
    out = []
    for name, info in table.items():
        prior = p.prior(name, priors[name], where=pwhere, table=table) if name in priors else None
        if check is not None:
            check(name, prior)
        if name in fixed:
            key = f"{fwhere}.{name}"
            v = p.number(key, fixed[name])
            lo, hi = info.domain
            if not lo <= v <= hi:
                raise p.error(key, f"a fixed {name} in its domain [{lo:g}, {hi:g}] "
                              f"{info.unit}", f"{v:g}")
            if prior is not None and not prior.contains(v):
                raise p.error(key, f"a fixed {name} that its prior {prior.describe()} "
                              f"({pwhere}.{name}) admits", f"{v:g}")
            out.append(ParameterSpec(name, info.unit, prior, v))
        elif prior is not None:
            out.append(ParameterSpec(name, info.unit, prior, None))
        else:
            out.append(_default_spec(name, info))
    return tuple(out)


def default_parameter_specs(table: Mapping[str, ParameterInfo]) -> tuple[ParameterSpec, ...]:
    """Every parameter of ``table`` with its default prior or fixed value, in its order."""
    return tuple(_default_spec(name, info) for name, info in table.items())


def spec_named(specs: Sequence[ParameterSpec], name: str) -> ParameterSpec:
    """The spec of parameter ``name`` among ``specs`` (:class:`KeyError` when absent)."""
    for p in specs:
        if p.name == name:
            return p
    raise KeyError(name)


def spec_tables(specs: Sequence[ParameterSpec]) -> dict[str, dict[str, Any]]:
    """``{"priors": ..., "fixed": ...}``: ``specs`` in the form of the TOML tables (JSON-ready)."""
    return {"priors": {p.name: p.prior.to_dict() for p in specs
                       if p.prior is not None and p.free},
            "fixed": {p.name: p.fixed for p in specs if not p.free}}


def _default_spec(name: str, info: ParameterInfo) -> ParameterSpec:
    if isinstance(info.default, Prior):
        return ParameterSpec(name, info.unit, info.default, None)
    return ParameterSpec(name, info.unit, None, float(info.default))

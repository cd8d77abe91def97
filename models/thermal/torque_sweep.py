"""The mean mesh stiffness and natural frequency swept over torque and backlash (seed 000).

The thermal closure ``Delta_1 + Delta_2`` of seed 000's hot state (:class:`ThermalClosure`,
:func:`seed_000_hot_state_closure`), the torque ranges where a backlash is jammed, and the sweep
of the mean mesh stiffness and natural frequency over torque and backlash that
:func:`rigtools.plots.thermal.thermal_figures` draws. Nothing here draws.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

import numpy as np

from models.geometry.gear_sets import GearSet, load_gear_set
from models.stiffness.load_distribution import contact_path_positions
from models.thermal.expansion import GearTemperature, thermal_deformation
from models.thermal.flash import flash_temperature
from models.thermal.natural_frequency import (
    NaturalFrequency,
    NaturalFrequencyModel,
    mesh_natural_frequency,
    prepare_natural_frequency,
)
from models.thermal.reference_state import ThermalReference
from models.thermal.thermoelastic import CRITICAL_GAP_ATOL_M, SEED_000_CHI, critical_gap

__all__ = [
    "TABLE_6_TORQUES_NM",
    "JamSpan",
    "ThermalClosure",
    "ThermalSweep",
    "default_backlash",
    "jammed_torque_spans",
    "seed_000_hot_state_closure",
    "thermal_sweep",
    "torque_grid",
]

#: Pinion torques of seed 000 Table 6 (N m), the runs whose natural frequency was measured.
TABLE_6_TORQUES_NM: Final = (3.3, 35.3, 183.4, 302.0)

_UM: Final = 1e6  # m -> um


def _num(x: float) -> str:
    return f"{x:g}"


# --- the thermal closure ---------------------------------------------------------------------
@dataclass(frozen=True)
class ThermalClosure:
    """The thermal closure a figure was computed with, and what it was read from.

    Attributes
    ----------
    total_m : float
        ``Delta_1 + Delta_2`` on the line of action (m), uniform along the path and the same at
        every torque of the figure.
    description : str
        How it was obtained (reading of the reference state, operating point), for the note
        under the figure.
    range_m : tuple of float, optional
        ``(min, max)`` of the closure along the path before it was averaged (m), if it was.
    """

    total_m: float
    description: str
    range_m: tuple[float, float] | None = None


def seed_000_hot_state_closure(
    gear_set: GearSet,
    *,
    torque_Nm: float = 302.0,
    pinion_speed_rpm: float = 1500.0,
    oil_temperature_C: float = 90.0,
    reference_temperature_C: float = 20.0,
) -> ThermalClosure:
    r"""Seed 000's hot-state closure: the path mean of ``Delta_1 + Delta_2`` at one run.

    The reading of :mod:`models.thermal.reference_state` that reproduces the seed's numbers:
    gears uniformly at the oil temperature, housing at the oil temperature (the centre distance
    grows with it, so only the gears' excess over the oil closes the backlash), the flash
    temperature (:func:`models.thermal.flash_temperature`, seed 000 friction and load share)
    counted as the local rise of the flank, the gears' own expansion coefficient. The mean is
    taken over seed 000's 52 points on the path of contact.

    Parameters
    ----------
    gear_set : GearSet
    torque_Nm : float
        Pinion torque of the run (N m); 302 N m is the seed's hottest Table 6 run.
    pinion_speed_rpm : float
        Pinion speed (1/min).
    oil_temperature_C : float
        Oil, bulk and housing temperature (deg C).
    reference_temperature_C : float
        Assembly temperature at which the backlash is defined (deg C).

    Returns
    -------
    ThermalClosure
        FZG-C at the defaults: 10.58 um (0.42 to 20.1 um along the path), ``c*`` = 10.27 um.
    """
    pair = gear_set.pair
    s = contact_path_positions(pair)
    ref = ThermalReference(reference_temperature_C, "follows-oil",
                           oil_temperature_C=oil_temperature_C, flash_counts_as_local_rise=True)
    flash = flash_temperature(pair, s, torque_Nm, pinion_speed_rpm,
                              bulk_temperature_C=oil_temperature_C)
    d = thermal_deformation(pair, s, ref, GearTemperature.uniform(oil_temperature_C),
                            flash=flash)
    xi = pair.pinion.material.thermal_expansion_per_K
    total = d.total_m
    description = (
        f"Thermal closure Δ₁+Δ₂ = {float(total.mean()) * _UM:.2f} µm, uniform along the path and "
        f"held fixed at every torque: mean over the path ({float(total.min()) * _UM:.2f} to "
        f"{float(total.max()) * _UM:.1f} µm) of seed 000's hot state at "
        f"{_num(torque_Nm)} N·m, {_num(pinion_speed_rpm)} min⁻¹, "
        f"{_num(oil_temperature_C)} °C oil.\n"
        f"Reference-state reading (SEED-NOTES 8): gears and housing at the oil temperature, "
        f"backlash defined at {_num(reference_temperature_C)} °C, so only the flash temperature "
        f"counted as the flanks' local rise closes it; ξ = {xi * 1e6:.3g}·10⁻⁶ /K."
    )
    return ThermalClosure(float(total.mean()), description,
                          (float(total.min()), float(total.max())))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive index ranges ``(a, b)`` of the runs of True in a 1-D bool array."""
    runs, start = [], None
    for i, v in enumerate([*mask.tolist(), False]):
        if v and start is None:
            start = i
        elif not v and start is not None:
            runs.append((start, i - 1))
            start = None
    return runs


def _root(t: np.ndarray, y: np.ndarray, i: int, j: int) -> float:
    """Torque where ``y`` (the smallest net deflection) crosses 0 between grid points i, j.

    The net deflection ``F' / q_max + c - c*`` is linear in the torque for a closure uniform
    along the path, so the linear interpolation is exact there.
    """
    yi, yj = float(y[i]), float(y[j])
    if yi == yj or not (math.isfinite(yi) and math.isfinite(yj)):
        return 0.5 * (float(t[i]) + float(t[j]))
    x = float(t[i]) + (0.0 - yi) * (float(t[j]) - float(t[i])) / (yj - yi)
    return min(max(x, float(min(t[i], t[j]))), float(max(t[i], t[j])))


@dataclass(frozen=True)
class JamSpan:
    """A torque range where one backlash is jammed by thermal growth.

    Attributes
    ----------
    lo_Nm, hi_Nm : float
        Ends of the range (N m).
    open_low : bool
        The range starts at the first torque of the grid (and is extended to 0: the jam always
        includes the lightest loads).
    open_high : bool
        The range runs to the last torque of the grid (its end there is not a jam boundary).
    """

    lo_Nm: float
    hi_Nm: float
    open_low: bool
    open_high: bool


def jammed_torque_spans(torque_Nm: np.ndarray, jammed: np.ndarray,
                        net_deflection_m: np.ndarray) -> list[JamSpan]:
    """Torque ranges where one backlash is jammed, ends at the zeros of the net deflection.

    Parameters
    ----------
    torque_Nm : numpy.ndarray
        Increasing torques of the grid (N m), shape ``(n,)``.
    jammed : numpy.ndarray of bool
        Jammed at each torque (``NaturalFrequency.jammed`` of one backlash), shape ``(n,)``.
    net_deflection_m : numpy.ndarray
        The smallest net deflection ``F' / q_max + c - c*`` at each torque (m)
        (``NaturalFrequency.min_net_deflection_m`` of that backlash), shape ``(n,)``.

    Returns
    -------
    list of JamSpan
        One per run of jammed torques, lowest first. A run that starts at the first torque
        extends to 0; an end between grid points is the zero of the net deflection there
        (exact: the net deflection is linear in the torque for a closure uniform along the
        path).
    """
    spans = []
    t, net = torque_Nm, net_deflection_m
    n = t.size
    for a, b in _runs(jammed):
        lo = 0.0 if a == 0 else _root(t, net, a - 1, a)
        hi = float(t[-1]) if b == n - 1 else _root(t, net, b, b + 1)
        spans.append(JamSpan(lo, hi, a == 0, b == n - 1))
    return spans


def default_backlash(c_star_m: float) -> tuple[float, ...]:
    """The backlash values of :func:`thermal_sweep` (m): 0, c*/2, c*, 2 c*, 40 um, 100 um.

    ``c_star_m`` is the critical compensation gap ``c*`` (m).
    """
    return (0.0, 0.5 * c_star_m, c_star_m, 2.0 * c_star_m, 40e-6, 100e-6)


def torque_grid(torque_max_Nm: float = 500.0, n: int = 500,
                extra_Nm: Sequence[float] = ()) -> np.ndarray:
    """Torques (N m): ``n`` equal steps up to ``torque_max_Nm``, with ``extra_Nm`` merged in.

    Parameters
    ----------
    torque_max_Nm : float
        Largest torque (N m), finite and > 0.
    n : int
        Equal steps from 0 (excluded) to ``torque_max_Nm``, >= 2.
    extra_Nm : sequence of float
        Torques to add (N m); those outside ``(0, torque_max_Nm]`` are dropped.

    Returns
    -------
    numpy.ndarray
        Sorted, unique torques (N m).
    """
    if not (math.isfinite(torque_max_Nm) and torque_max_Nm > 0):
        raise ValueError(f"`torque_max_Nm` must be finite and > 0, was {torque_max_Nm!r}")
    if isinstance(n, bool) or not isinstance(n, int) or n < 2:
        raise ValueError(f"`n` must be an integer >= 2, was {n!r}")
    base = np.linspace(0.0, torque_max_Nm, n + 1)[1:]
    extra = np.asarray([x for x in extra_Nm if 0 < x <= torque_max_Nm], dtype=float)
    return np.unique(np.concatenate([base, extra]))


@dataclass(frozen=True)
class ThermalSweep:
    """The mean mesh stiffness and natural frequency over torque and backlash.

    What :func:`thermal_sweep` computed (drawn by :func:`rigtools.plots.thermal.thermal_figures`).

    Attributes
    ----------
    gear_set : GearSet
        The gear set swept.
    closure : ThermalClosure
        The thermal closure, uniform along the path and the same at every torque.
    c_star : float
        Critical compensation gap ``c* = (1 - chi)(Delta_1 + Delta_2)`` (m).
    backlash : numpy.ndarray
        Total backlash values (m), shape ``(n_backlash,)``.
    model : NaturalFrequencyModel
        The prepared natural-frequency model of the pair.
    torque : numpy.ndarray
        Pinion torques (N m), shape ``(n_torque,)``, increasing.
    result : NaturalFrequency
        Mean stiffness, natural frequency and jammed state, shape ``(n_backlash, n_torque)``.
    """

    gear_set: GearSet
    closure: ThermalClosure
    c_star: float
    backlash: np.ndarray
    model: NaturalFrequencyModel
    torque: np.ndarray
    result: NaturalFrequency


def thermal_sweep(
    gear_set: str | Path | GearSet = "fzg-c",
    backlash_m: Sequence[float] | None = None,
    torque_max_Nm: float = 500.0,
    n_torques: int = 500,
    thermal_closure: ThermalClosure | None = None,
    chi: float = SEED_000_CHI,
) -> ThermalSweep:
    """The mean mesh stiffness and natural frequency of a gear set over torque and backlash.

    The thermal closure is seed 000's hot state (:func:`seed_000_hot_state_closure`) unless
    given; it is held fixed over the torque sweep, uniform along the path. Ishikawa's ``k_EP``
    without the contact term and seed 000's load share
    (:func:`~models.thermal.natural_frequency.prepare_natural_frequency`).

    Parameters
    ----------
    gear_set : str, path or GearSet
        A shipped gear-set name, a gear-set file, or a loaded gear set.
    backlash_m : sequence of float, optional
        Total backlash values (m); default :func:`default_backlash` of ``c*``.
    torque_max_Nm : float
        Largest pinion torque (N m).
    n_torques : int
        Steps of the torque grid (:func:`torque_grid`); the Table 6 torques and points just
        above each jam boundary (``T = r_b1 (c* - c) max_j(k_EP / R)``) are added to it.
    thermal_closure : ThermalClosure, optional
        ``Delta_1 + Delta_2`` and its description.
    chi : float
        Thermoelastic correction factor (-); seed 000's 0.0285.

    Returns
    -------
    ThermalSweep

    Raises
    ------
    ValueError
        On a ``thermal_closure`` that is not a :class:`ThermalClosure`, or a bad torque grid.
    """
    if not isinstance(gear_set, GearSet):
        gear_set = load_gear_set(gear_set)
    closure = seed_000_hot_state_closure(gear_set) if thermal_closure is None \
        else thermal_closure
    if not isinstance(closure, ThermalClosure):
        raise ValueError(f"`thermal_closure` must be a ThermalClosure, was "
                         f"{type(closure).__name__}")
    c_star = float(critical_gap(closure.total_m, chi))
    backlash = np.asarray(default_backlash(c_star) if backlash_m is None else backlash_m,
                          dtype=float)
    pair = gear_set.pair
    model = prepare_natural_frequency(pair)

    # jam boundaries T = r_b1 (c* - c) max_j(k_EP / R): refine just above them
    q_max = float(np.max(model.k_EP_N_per_m / model.load_share))
    edges = [model.base_radius_pinion_m * (c_star - c) * q_max for c in backlash.tolist()
             if c < c_star - CRITICAL_GAP_ATOL_M]
    extra = [*TABLE_6_TORQUES_NM]
    for edge in edges:
        extra.extend((edge * (1.0 + np.geomspace(1e-5, 2e-2, 24))).tolist())
    torque = torque_grid(torque_max_Nm, n_torques, extra)
    result = mesh_natural_frequency(model, torque, closure.total_m, backlash[:, None], chi)
    return ThermalSweep(gear_set, closure, c_star, backlash, model, torque, result)

"""Simulation-based calibration of the SDOF run-up calibration (Talts et al. 2018).

Each simulation draws ``zeta``, the stiffness scale ``s``, the model error (shared by the
channels at a point, correlated along the sweep over its length), its correlation length, the
channel error and one gain per channel from the default
``[calibration.runup]`` priors (the backlash fixed at 136 um, so that no draw depends on a
parameter a run-up without back-side impact cannot identify; the fluctuation scale at its
default 1), sweeps a VVMS run-up of the Kahraman-Blankenship pair
at 300 N m over ``0.6-1.45`` times the true natural frequency, up then down, with the plain
per-walker sweep (:func:`models.dynamics.walkers.sweep_walkers_reference`: not the compiled
kernel the calibration uses), multiplies by the gains and the two log-normal errors, fits it
with :func:`rigtools.calibration.runup_api.calibrate_runup_data` and records, for ``zeta``,
the mesh natural frequency ``f_n`` and the three error parameters: whether the central 90 % interval
covers the truth and the rank of the truth among ``L = 99`` evenly spaced posterior draws.

Checks (:func:`check`): 90 % coverage in [0.85, 0.95]; the rank histogram (10 bins) passes a
chi-square test of uniformity at 1 %.

Usage::

    python tests/calibration/sbc_runup.py --n 100 --seed 0 --jobs 2 --out sbc_runup.json

(``tests/calibration/test_sbc_runup.py`` runs 100 as a slow test and 6 in the default suite;
:func:`simulate_curve` also makes the synthetic run-ups of ``test_runup_calibration.py``.)

References
----------
.. [1] S. Talts, M. Betancourt, D. Simpson, A. Vehtari, A. Gelman, "Validating Bayesian
   inference algorithms with simulation-based calibration", arXiv:1804.06788 (2018).
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from sbc_common import N_RANK_DRAWS, emit_report, parse_cli, rank_coverage

from models.dynamics.walkers import cycle_bank, sweep_walkers_reference
from models.geometry import load_gear_set
from rigtools.calibration import CalibrationError, default_config
from rigtools.calibration.runup_api import calibrate_runup_data
from rigtools.calibration.runup_config import RunUpSettings
from rigtools.calibration.runup_data import RunUpCurve, RunUpData
from rigtools.calibration.runup_forward import acceleration_arms, window_path
from rigtools.calibration.runup_likelihood import error_gaps, sample_model_error

GEAR_SET = "kahraman-blankenship"
TORQUE_NM = 300.0
BACKLASH_UM = 136.0
CHANNELS = ("accel_x", "accel_y", "accel_z")
QUANTITIES = ("zeta", "mesh_natural_frequency_Hz", "model_error", "model_error_length",
              "channel_error")
_DRAWN = ("zeta", "mesh_stiffness_scale", "model_error", "model_error_length", "channel_error")


def simulate_curve(kind: str, torque_Nm: float, *, zeta: float, stiffness_scale: float,
                   gains: Sequence[float], model_error: float, seed: int,
                   channel_error: float = 0.0, model_error_length: float = 0.0,
                   points_per_direction: int = 40, span: tuple[float, float] = (0.6, 1.45),
                   backlash_um: float = BACKLASH_UM, fluctuation_scale: float = 1.0,
                   run_id: str = "sim", channels: Sequence[str] = CHANNELS) -> RunUpCurve:
    """A synthetic run-up: the plain sweep of ``kind``, times the gains, log-normal errors.

    ``log A_ci = log G_c + log mu_i + delta_i + channel_error e_ci`` with ``e`` standard
    Normal and ``delta`` shared by the channels at a point, sd ``model_error``, correlated
    along each direction over ``model_error_length`` in ``ln f_m``
    (:func:`~rigtools.calibration.runup_likelihood.sample_model_error`; 0: independent).

    The path runs from ``span[0]`` to ``span[1]`` times the true natural frequency
    ``sqrt(s kbar_F0 / m_e) / 2 pi`` (log-spaced) and back; the plain sweep runs it as a rig
    ramps, through continuation nodes no more than
    :data:`~rigtools.calibration.runup_forward.MAX_PATH_STEP` apart
    (:func:`~rigtools.calibration.runup_forward.window_path`), and ``mu`` is read at the points.
    """
    pair = load_gear_set(GEAR_SET).pair
    bank = cycle_bank(pair, torque_Nm, kind)
    fn = float(bank.natural_frequency_Hz(stiffness_scale))
    up = fn * np.exp(np.linspace(math.log(span[0]), math.log(span[1]), points_per_direction))
    f = np.concatenate([up, up[::-1]])
    n = points_per_direction
    direction = np.array(["up"] * n + ["down"] * n, dtype=object)
    t = np.linspace(0.0, 10.0, f.size)
    nan = np.full((len(channels), f.size), np.nan)
    curve = RunUpCurve(run_id=run_id, gear_set=GEAR_SET, torque_Nm=float(torque_Nm),
                       channels=tuple(channels), mesh_frequency_Hz=f, time_s=t,
                       direction=direction, observed=nan,
                       harmonics=np.full((len(channels), f.size, 3), np.nan))
    path = window_path(curve)
    sw = sweep_walkers_reference(bank, path.mesh_frequency_Hz, zeta=[zeta],
                                 stiffness_scale=[stiffness_scale],
                                 fluctuation_scale=[fluctuation_scale],
                                 backlash_m=[backlash_um * 1e-6])
    mu = path.power_mean(acceleration_arms(sw.amplitude_m[0], path.mesh_frequency_Hz))
    rng = np.random.default_rng([seed, 7])
    g = np.asarray(gains, dtype=float)[:, None]
    gaps = error_gaps(f, direction)
    shared = sample_model_error(np.array([model_error]), np.array([model_error_length]), gaps,
                                rng)[0]
    own = channel_error * rng.standard_normal((len(channels), f.size))
    return replace(curve, observed=g * mu[None, :] * np.exp(shared[None, :] + own))


@dataclass(frozen=True)
class Settings:
    """Sampler and data settings of one simulation."""

    walkers: int = 32
    max_steps: int = 20000
    check_every: int = 100
    map_starts: int = 8
    points_per_direction: int = 100


def config_for(settings: Settings, models: Sequence[str] = ("vvms",), *,
               fix_backlash: bool = True) -> Any:
    """The calibration configuration of the simulations (backlash fixed unless told)."""
    base = default_config()
    ru = base.runup
    params = tuple(replace(p, fixed=BACKLASH_UM) if p.name == "backlash" and fix_backlash
                   else p for p in ru.parameters)
    ru = replace(ru, walkers=settings.walkers, max_steps=settings.max_steps, parameters=params)
    assert isinstance(ru, RunUpSettings)
    return replace(base, models=tuple(models), runup=ru, check_every=settings.check_every,
                   map_starts=settings.map_starts)


def one(args: tuple[int, Settings]) -> dict[str, Any]:
    """One simulation: draw, simulate, fit; coverage and ranks (or the refusal)."""
    i, settings = args
    cfg = config_for(settings)
    rng = np.random.default_rng([i, 11])
    ru = cfg.runup
    draw = {n: float(ru.parameter(n).prior.sample(rng, 1)[0]) for n in _DRAWN}
    while not 0.3 <= draw["mesh_stiffness_scale"] <= 3.0:   # the prior as the banks cut it
        draw["mesh_stiffness_scale"] = float(
            ru.parameter("mesh_stiffness_scale").prior.sample(rng, 1)[0])
    gains = ru.parameter("gain").prior.sample(rng, len(CHANNELS))
    pair = load_gear_set(GEAR_SET).pair
    bank = cycle_bank(pair, TORQUE_NM, "vvms")
    truth = {"zeta": draw["zeta"], "model_error": draw["model_error"],
             "model_error_length": draw["model_error_length"],
             "channel_error": draw["channel_error"],
             "mesh_natural_frequency_Hz": float(bank.natural_frequency_Hz(
                 draw["mesh_stiffness_scale"]))}
    curve = simulate_curve("vvms", TORQUE_NM, zeta=draw["zeta"],
                           stiffness_scale=draw["mesh_stiffness_scale"], gains=gains,
                           model_error=draw["model_error"],
                           channel_error=draw["channel_error"],
                           model_error_length=draw["model_error_length"], seed=i,
                           points_per_direction=settings.points_per_direction)
    t0 = time.perf_counter()
    try:
        res = calibrate_runup_data(RunUpData(curves=(curve,), refused={}), {"sim": pair}, cfg,
                                   seed=i)
    except CalibrationError as exc:
        return {"i": i, "refused": str(exc)}
    fit = res.fits["vvms"]
    post = fit.posterior
    p = post.unpack(fit.run.samples())
    draws = {"zeta": p["zeta"], "model_error": p["model_error"],
             "model_error_length": p["model_error_length"],
             "channel_error": p["channel_error"],
             "mesh_natural_frequency_Hz": post.forward.natural_frequency_Hz(
                 p["mesh_stiffness_scale"])}
    out: dict[str, Any] = {"i": i, "seconds": time.perf_counter() - t0,
                           "converged": fit.converged, "truth": truth}
    for q in QUANTITIES:
        x = np.sort(np.asarray(draws[q], dtype=float).ravel())
        lo, hi = np.quantile(x, [0.05, 0.95])
        pick = x[np.linspace(0, x.size - 1, N_RANK_DRAWS).round().astype(int)]
        out[q] = {"covered": bool(lo <= truth[q] <= hi),
                  "rank": int(np.sum(pick < truth[q])),
                  "median": float(np.median(x)), "q05": float(lo), "q95": float(hi)}
    return out


def run(n: int, *, seed: int = 0, settings: Settings | None = None,
        jobs: int = 1) -> list[dict[str, Any]]:
    """``n`` simulations (seeds ``seed .. seed + n - 1``)."""
    s = Settings() if settings is None else settings
    tasks = [(seed + k, s) for k in range(n)]
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as ex:
            return list(ex.map(one, tasks))
    return [one(t) for t in tasks]


def check(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Coverage and rank-histogram uniformity per quantity."""
    fitted = [r for r in results if "refused" not in r]
    report: dict[str, Any] = {"n": len(results), "fitted": len(fitted),
                              "refused": [r for r in results if "refused" in r],
                              "converged": sum(bool(r["converged"]) for r in fitted)}
    for q in QUANTITIES:
        summary = rank_coverage(fitted, q)
        report[q] = {"coverage_90": summary.coverage_90, "chi2_p": summary.chi2_p,
                     "histogram": summary.rank_counts.tolist()}
    return report


def main(argv: list[str] | None = None) -> int:
    a = parse_cli(__doc__.splitlines()[0], argv)
    results = run(a.n, seed=a.seed, jobs=a.jobs)
    return emit_report(check(results), results, a.out, QUANTITIES, indent=2)


if __name__ == "__main__":
    sys.exit(main())

"""The SDOF run-up calibration end to end on synthetic run-ups (issue 20 items 1-3, 5, 7).

Synthetic data: the plain per-walker sweep (``sweep_walkers_reference``, not the compiled
kernel the calibration uses) of a known model, times a gain per channel, with log-normal
noise (:func:`sbc_runup.simulate_curve`). The default suite runs reduced versions (one
torque, 20 points per direction, 10 walkers, a few dozen steps: the chains are not converged,
which the result flags); the slow test runs the full one (three torques, the three models,
VVMS and LSTE sampled to convergence, FVMS for a capped number of steps: its docstring says
why).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from sbc_runup import GEAR_SET, Settings, config_for, simulate_curve

from models.dynamics.walkers import cycle_bank
from models.geometry import load_gear_set
from rigtools.calibration import CalibrationError, default_config
from rigtools.calibration.comparison import compare_variants
from rigtools.calibration.runup_api import calibrate_runup_data, runup_loo_data
from rigtools.calibration.runup_data import RunUpData
from rigtools.calibration.runup_outputs import RUNUP_DIR, RunUpResult
from rigtools.calibration.runup_summary import NO_BACKSIDE_STATEMENT
from rigtools.schemas import iter_errors

TRUTH = {"zeta": 0.025, "stiffness_scale": 0.9, "model_error": 0.1, "channel_error": 0.03,
         "gains": (1e-2, 4e-3, 7e-3)}


def _pair():
    return load_gear_set(GEAR_SET).pair


def _fit(curves: tuple, models: tuple[str, ...], settings: Settings, *, seed: int = 3,
         fixed_backlash: bool = False, refused: dict[str, str] | None = None,
         outdir: object = None) -> RunUpResult:
    cfg = config_for(settings, models=models, fix_backlash=fixed_backlash)
    pair = _pair()
    data = RunUpData(curves=tuple(curves), refused=dict(refused or {}))
    return calibrate_runup_data(data, {c.run_id: pair for c in curves}, cfg, seed=seed,
                                outdir=outdir)


def test_vvms_truth_is_preferred_to_fvms_and_the_outputs_hold_what_the_figure_needs(
        tmp_path) -> None:
    curve = simulate_curve("vvms", 300.0, zeta=TRUTH["zeta"],
                           stiffness_scale=TRUTH["stiffness_scale"], gains=TRUTH["gains"],
                           model_error=TRUTH["model_error"],
                           channel_error=TRUTH["channel_error"], seed=1,
                           points_per_direction=20, run_id="KB-300")
    refusal = "run 'KB-bad': 3 usable speed points, fewer than min_speed_points = 20"
    res = _fit((curve,), ("vvms", "fvms"), Settings(walkers=12, max_steps=60, map_starts=1),
               refused={"KB-bad": refusal}, outdir=tmp_path)
    # comparison: the numbers and both checks. The chains are 60 steps from the MAP and not
    # converged, so the elpd ranking is not asserted here (the slow test asserts it on
    # converged chains): VVMS's MAP sits on the truth's needle, where the walkers that have
    # not yet mixed put a jump on the wrong side of one point (pointwise log density -50 to
    # -110 at it, Pareto k far above 0.7), and the statement must say so.
    v = res.comparison.variants
    print(f"elpd vvms {v['vvms']['elpd_loo']:.1f} (se {v['vvms']['se']:.1f}, Pareto k max "
          f"{v['vvms']['pareto_k_max']:.2f}), fvms {v['fvms']['elpd_loo']:.1f}; MAP "
          f"{res.fits['vvms'].run.map_estimate.log_prob:.1f} against "
          f"{res.fits['fvms'].run.map_estimate.log_prob:.1f}")
    assert res.fits["vvms"].run.map_estimate.log_prob > \
        res.fits["fvms"].run.map_estimate.log_prob + 20.0
    assert {v[m]["rank"] for m in v} == {0, 1}
    for m in v:
        assert (v[m]["n_pareto_k_bad"] > 0) == (v[m]["pareto_k_max"] > 0.7)
        if v[m]["n_pareto_k_bad"]:
            assert f"{m} ({v[m]['n_pareto_k_bad']} of 40)" in res.comparison.statement
    assert res.blocked_comparison is not None and "Blocked check" in res.statement
    # item 7: the refused run is reported, not raised
    assert res.refused == {"KB-bad": refusal}
    assert any("KB-bad" in w for w in res.warnings)
    # identifiability: no back-side impact -> the backlash is not reported
    s = res.fits["vvms"].summary
    b = s["parameters"]["backlash"]
    assert b["identified"] is False and b["q05"] is None and b["q95"] is None
    assert b["mean"] is None and NO_BACKSIDE_STATEMENT in b["statement"]
    assert s["backlash"]["backside_impact_probability"] < 0.05
    assert any(NO_BACKSIDE_STATEMENT in w for w in res.warnings)
    assert s["parameters"]["zeta"]["identified"] is True
    assert s["parameters"]["fluctuation_scale"]["fixed"] == 1.0
    fn = s["derived"]["mesh_natural_frequency_Hz"]
    bank = cycle_bank(_pair(), 300.0, "vvms")
    true_fn = float(bank.natural_frequency_Hz(TRUTH["stiffness_scale"]))
    assert abs(fn["q50"] - true_fn) < 0.03 * true_fn
    assert "mesh_natural_frequency_Hz@KB-300" in s["derived"]
    assert "k_ref" in s["conventions"] and "m_e" in s["conventions"]
    assert s["converged"] is False and any("not converged" in w for w in res.warnings)
    # the predictive the figure draws
    p = res.fits["vvms"].predictive_for("KB-300")
    assert p.arms_q05.shape == p.observed.shape == (3, 40)
    assert np.all(p.arms_q05 <= p.arms_q50) and np.all(p.arms_q50 <= p.arms_q95)
    inside = (p.observed >= p.arms_q05) & (p.observed <= p.arms_q95)
    assert inside.mean() > 0.7
    assert set(p.jump_measured_Hz) == {"up", "down"} and set(p.jump_model_Hz) == {"up", "down"}
    assert p.jump_measured_Hz["up"] is not None and p.jump_model_Hz["up"] is not None
    # the points place a jump between two neighbours: an interval, not a point, around it
    for d in ("up", "down"):
        j, m = p.jump_model_Hz[d], p.jump_measured_Hz[d]
        assert j is not None and m is not None
        assert j["q05"] < j["q50"] < j["q95"] and j["q05"] < m < j["q95"]
    # pointwise log-likelihood: one per observed (run, point), its channels together
    assert res.fits["vvms"].log_likelihood.shape[-1] == 40
    assert res.fits["vvms"].arms_predictive.shape[-1] == 3 * 40
    # files
    root = tmp_path / RUNUP_DIR
    for m in ("vvms", "fvms"):
        summary = json.loads((root / m / "summary.json").read_text())
        assert iter_errors(summary, "runup_summary.schema.json") == []
        assert (root / m / "posterior.nc").is_file()
    comp = json.loads((root / "comparison.json").read_text())
    assert comp["pointwise"]["variants"]["vvms"]["rank"] == v["vvms"]["rank"]
    assert (root / "comparison.csv").read_text().splitlines()[0].startswith("model,elpd_loo")
    assert (root / "chains.h5").is_file()
    assert json.loads(json.dumps(res.to_dict()))["models"]["fvms"]["model"] == "fvms"


def test_a_ramp_below_the_resonance_is_named_and_a_rerun_resumes(tmp_path) -> None:
    curve = simulate_curve("vvms", 300.0, zeta=TRUTH["zeta"],
                           stiffness_scale=TRUTH["stiffness_scale"], gains=TRUTH["gains"],
                           model_error=0.05, seed=2, points_per_direction=12,
                           span=(0.35, 0.7), run_id="KB-slow")
    settings = Settings(walkers=10, max_steps=30, map_starts=1)
    res = _fit((curve,), ("vvms",), settings, fixed_backlash=True, outdir=tmp_path)
    assert any(w.startswith("run KB-slow:") and "resonance" in w for w in res.warnings), \
        res.warnings
    again = _fit((curve,), ("vvms",), settings, fixed_backlash=True, outdir=tmp_path)
    assert again.fits["vvms"].run.resumed_from == 30
    np.testing.assert_array_equal(again.fits["vvms"].samples, res.fits["vvms"].samples)


def test_no_usable_runup_is_an_error_only_when_models_are_asked_for() -> None:
    data = RunUpData(curves=(), refused={"r1": "run 'r1': no usable speed signal"})
    with pytest.raises(CalibrationError, match=r"no usable run-up.*r1"):
        calibrate_runup_data(data, {}, config_for(Settings(), models=("vvms",)))
    empty = calibrate_runup_data(data, {}, default_config())
    assert empty.fits == {} and empty.refused == data.refused
    assert "no SDOF models" in empty.statement


#: Steps FVMS, the wrong model, is sampled for in the full test (module notes of the test).
FVMS_STEPS = 3000


def three_torques(settings: Settings, wrong_steps: int, points: int = 50) -> tuple:
    """VVMS run-ups at 100/200/300 N m; VVMS and LSTE fitted with ``settings``, FVMS capped.

    Returns ``(result of vvms and lste, result of fvms, their PSIS-LOO comparison, f_n)``.
    """
    bank = cycle_bank(_pair(), 200.0, "vvms")
    true_fn = float(bank.natural_frequency_Hz(TRUTH["stiffness_scale"]))
    curves = tuple(simulate_curve("vvms", t, zeta=TRUTH["zeta"],
                                  stiffness_scale=TRUTH["stiffness_scale"],
                                  gains=TRUTH["gains"], model_error=TRUTH["model_error"],
                                  channel_error=TRUTH["channel_error"], seed=10 + i,
                                  points_per_direction=points, run_id=f"KB-{t:g}")
                   for i, t in enumerate((100.0, 200.0, 300.0)))
    right = _fit(curves, ("vvms", "lste"), settings, fixed_backlash=False)
    wrong = _fit(curves, ("fvms",), replace(settings, max_steps=wrong_steps),
                 fixed_backlash=False)
    fits = {**right.fits, **wrong.fits}
    comparison = compare_variants({m: runup_loo_data(f) for m, f in fits.items()})
    return right, wrong, comparison, true_fn


@pytest.mark.slow
def test_vvms_runups_at_three_torques_full() -> None:
    """Issue 20 item 3: three torques, the three models, VVMS and LSTE to convergence.

    FVMS is the wrong model here, and its posterior on VVMS data is misspecified and
    multimodal (a backlash of a few um against the wide-gap plateau): in session 14 it was
    still not converged after 7800 steps and 85 minutes of sampling, so with the default cap
    of 20000 steps the test would not end in a working day. It is sampled for
    :data:`FVMS_STEPS`; its elpd then rests on unconverged chains, and the test asks for the
    best of VVMS and LSTE to lead it by more than four standard errors of the difference.
    """
    right, _, comparison, true_fn = three_torques(Settings(), FVMS_STEPS)
    v = comparison.variants
    best = max(("vvms", "lste"), key=lambda m: v[m]["elpd_loo"])
    diff = v[best]["elpd_loo"] - v["fvms"]["elpd_loo"]
    print(f"{best} - fvms: elpd difference {diff:.1f} (dse {v['fvms']['dse']:.1f}); Pareto k "
          f"max {[v[m]['pareto_k_max'] for m in ('fvms', 'vvms', 'lste')]}")
    print(comparison.statement)
    assert diff > 4 * v["fvms"]["dse"]
    s = right.fits["vvms"].summary
    assert right.fits["vvms"].converged
    z = s["parameters"]["zeta"]
    assert z["q05"] <= TRUTH["zeta"] <= z["q95"]
    fn = s["derived"]["mesh_natural_frequency_Hz"]
    assert fn["q05"] <= true_fn <= fn["q95"]
    assert fn["q95"] - fn["q05"] < 0.1 * true_fn
    assert not math.isnan(fn["ess_bulk"])

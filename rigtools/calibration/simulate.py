"""Synthetic observation tables drawn through the forward model (tests, SBC, planning).

:func:`simulate_observations` writes the rows a campaign would give ``rigtools calibrate``:
one ``run`` row per run and ``natural_frequency`` rows per channel, with

* the mesh mode at ``f_pred (1 + model_error eps)`` (one ``eps ~ N(0, 1)`` per run, shared
  by the channels), seen by each channel with the fit scatter ``fit_sd_rel f`` and reported
  ``f_n_std_Hz = fit_sd_rel f``; present with the likelihood's detection probability
  (``detection_probability`` inside the band, falling smoothly to 0 outside it), absent when
  the run is jammed (censored reading);
* load-independent housing modes at fixed frequencies on every channel (``housing_modes_Hz``),
  with a prominence above the mesh mode's (the tallest peak is then the wrong one);
* optionally spurious peaks uniform in the band (Poisson, ``spurious_per_run``).

It is the data-generating process the likelihood assumes, plus the housing modes (which the
likelihood treats as uniform background although they sit at fixed frequencies), so it
serves simulation-based calibration; tests of the forward model itself use
:func:`models.thermal.mesh_natural_frequency_scalar` instead.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from models.geometry import GearPair
from models.thermal import ThermalReference
from rigtools.calibration.config import ThermalModel, Variant
from rigtools.calibration.forward import predict, prepare_forward
from rigtools.calibration.likelihood import LikelihoodSettings
from rigtools.calibration.likelihood import detection_probability as p_detect

__all__ = ["simulate_observations"]


def simulate_observations(
    pair: GearPair,
    run_ids: Sequence[str],
    torque_Nm: ArrayLike,
    bulk_temperature_C: ArrayLike,
    truth: Mapping[str, float],
    *,
    rng: np.random.Generator,
    variant: Variant = "secant_path",
    thermal_model: ThermalModel = "linear",
    reference: ThermalReference | None = None,
    channels: Sequence[str] = ("accel_1", "accel_2"),
    fit_sd_rel: float = 0.004,
    detection_probability: float = 0.9,
    band_Hz: tuple[float, float] = (300.0, 15000.0),
    housing_modes_Hz: Sequence[float] = (),
    housing_prominence_dB: float = 24.0,
    mesh_prominence_dB: float = 15.0,
    spurious_per_run: float = 0.0,
    campaign: str = "synthetic",
) -> pd.DataFrame:
    """An observations table (the columns the calibration reads) from known parameters.

    Parameters
    ----------
    pair : GearPair
    run_ids : sequence of str
    torque_Nm, bulk_temperature_C : array_like
        Conditions per run.
    truth : mapping
        ``backlash`` (um), ``closure_coefficient``, ``stiffness_scale``, ``chi``,
        ``model_error`` (the parameter names of :mod:`rigtools.calibration.config`).
    rng : numpy.random.Generator
    variant, thermal_model, reference
        Forward model (module :mod:`rigtools.calibration.forward`).
    channels : sequence of str
    fit_sd_rel : float
        Relative scatter and reported sd of a peak's frequency.
    detection_probability : float
        Probability that the mesh mode shows (in band, not jammed).
    band_Hz : (float, float)
        Band of spurious peaks and of detection (as
        :func:`rigtools.calibration.likelihood.detection_probability`).
    housing_modes_Hz : sequence of float
        Load-independent modes on every channel.
    housing_prominence_dB, mesh_prominence_dB : float
    spurious_per_run : float
        Mean number of spurious peaks per run and channel.
    campaign : str

    Returns
    -------
    pandas.DataFrame
        Columns ``campaign, run_id, channel, quantity, mode_index, torque_Nm,
        bulk_temperature_C, oil_temperature_C, f_n_Hz, f_n_std_Hz, zeta, peak_kind,
        prominence_dB, quality_flags, status, message``; an extra column ``truth_is_mesh``
        marks the mesh-mode rows.
    """
    t = np.asarray(torque_Nm, dtype=float)
    th = np.asarray(bulk_temperature_C, dtype=float)
    fm = prepare_forward(pair, t, th, variant=variant, thermal_model=thermal_model,
                         reference=reference)
    pred = predict(fm, truth["backlash"] * 1e-6, truth["closure_coefficient"],
                   truth["stiffness_scale"], truth["chi"])
    f_model = pred.f_n_Hz[0]
    settings = LikelihoodSettings(band_Hz, detection_probability)
    eps = rng.standard_normal(t.size)
    f_true = f_model * (1.0 + truth["model_error"] * eps)
    rows: list[dict[str, object]] = []

    def base(i: int) -> dict[str, object]:
        return {"campaign": campaign, "run_id": run_ids[i], "torque_Nm": float(t[i]),
                "bulk_temperature_C": float(th[i]), "oil_temperature_C": float(th[i]),
                "quality_flags": "", "message": ""}

    for i in range(t.size):
        rows.append({**base(i), "channel": None, "quantity": "run", "status": "ok"})
        f = f_true[i]
        p_shown = float(p_detect(f_true[i:i + 1], settings)[0]) if np.isfinite(f) else 0.0
        shown = rng.random() < p_shown
        for ch in channels:
            peaks: list[tuple[float, float, bool]] = []
            if shown:
                peaks.append((f * (1.0 + fit_sd_rel * rng.standard_normal()),
                              mesh_prominence_dB, True))
            for h in housing_modes_Hz:
                peaks.append((h * (1.0 + fit_sd_rel * rng.standard_normal()),
                              housing_prominence_dB, False))
            for _ in range(rng.poisson(spurious_per_run)):
                peaks.append((rng.uniform(*band_Hz), 8.0, False))
            peaks.sort()
            for k, (fk, prom, is_mesh) in enumerate(peaks):
                rows.append({**base(i), "channel": ch, "quantity": "natural_frequency",
                             "mode_index": k, "f_n_Hz": fk, "f_n_std_Hz": fit_sd_rel * fk,
                             "zeta": 0.02, "peak_kind": "structural", "prominence_dB": prom,
                             "status": "ok", "truth_is_mesh": is_mesh})
    cols = ["campaign", "run_id", "channel", "quantity", "mode_index", "torque_Nm",
            "bulk_temperature_C", "oil_temperature_C", "f_n_Hz", "f_n_std_Hz", "zeta",
            "peak_kind", "prominence_dB", "quality_flags", "status", "message",
            "truth_is_mesh"]
    df = pd.DataFrame.from_records(rows, columns=cols)
    df["mode_index"] = df["mode_index"].astype("Int64")
    df["truth_is_mesh"] = df["truth_is_mesh"].astype("boolean")
    return df

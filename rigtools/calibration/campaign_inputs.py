"""A campaign's calibration: what the campaign file says, turned into the calibration's inputs.

:func:`calibrate` is the entry point the issue names, ``calibrate(campaign, observations)``:
the campaign (a loaded :class:`~rigtools.campaign.Campaign` or the path of its TOML) gives the
gear pair, the ``[calibration]`` block (:func:`~rigtools.calibration.parse_calibration_block`,
errors naming its lines) and the ``[thermal]`` reference state; the observations are a table,
the path of one (``rigtools observe``'s parquet), the
:class:`~rigtools.campaign.observation_table.Observations` of ``observe_campaign``, or None (the
campaign is observed first). The sampling itself is
:func:`rigtools.calibration.api.calibrate_observations`.

The natural-frequency calibration is of one gear pair, the campaign's: runs whose
``[[run]] gear_set`` names another gear set (:meth:`~rigtools.campaign.Campaign.gear_for`) are
left out of it (:func:`campaign_gear_rows`), each with a warning naming the run and its gear
set; the SDOF run-up calibration uses them, each on its own pair.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TypeAlias

import pandas as pd

from models.thermal import ThermalReference
from rigtools.calibration.api import calibrate_observations
from rigtools.calibration.config import CalibrationConfig, parse_calibration_block
from rigtools.calibration.result import CalibrationResult
from rigtools.campaign.manifest import Campaign, load_campaign
from rigtools.campaign.observation_table import Observations
from rigtools.campaign.thermal_state import thermal_reference

__all__ = ["ObservationsInput", "calibrate", "campaign_config", "campaign_gear_rows",
           "campaign_observations", "campaign_reference"]

#: What ``observations`` may be.
ObservationsInput: TypeAlias = pd.DataFrame | Observations | str | Path | None


def campaign_reference(campaign: Campaign) -> ThermalReference | None:
    """The campaign's ``[thermal]`` reference state for the calibration, None without one.

    With ``housing = "follows-oil"`` the forward model places each run's housing at that run's
    logged oil temperature (:mod:`rigtools.calibration.forward`); the reference is built at the
    reference temperature only because the state needs an oil temperature to exist.
    """
    th = campaign.thermal
    if th.reference_temperature_C is None:
        return None
    if th.housing == "follows-oil":
        return thermal_reference(campaign, oil_temperature_C=th.reference_temperature_C)
    return thermal_reference(campaign)


def campaign_gear_rows(campaign: Campaign, observations: pd.DataFrame
                       ) -> tuple[pd.DataFrame, dict[str, str]]:
    """The rows of the runs on the campaign's gear set, and why the others are left out.

    Parameters
    ----------
    campaign : Campaign
    observations : pandas.DataFrame
        The observations table.

    Returns
    -------
    table : pandas.DataFrame
        ``observations`` without the rows of runs whose ``[[run]] gear_set`` is another gear
        set than ``[campaign] gear_set`` (the same object when no row is dropped). Rows of run
        ids the campaign does not list are kept.
    left_out : dict
        Run id -> why it is left out (naming its gear set), in campaign order.
    """
    left_out = {r.id: (f"on gear set {r.gear_set!r} ([[run]] gear_set), not the campaign's "
                       f"{campaign.gear_set!r}: left out of the natural-frequency calibration "
                       "(the SDOF run-up calibration uses it)")
                for r in campaign.runs if not campaign.on_campaign_gear(r.id)}
    present = set(observations["run_id"].astype(str)) if left_out else set()
    left_out = {k: v for k, v in left_out.items() if k in present}
    if not left_out:
        return observations, {}
    keep = ~observations["run_id"].astype(str).isin(list(left_out))
    return observations.loc[keep].reset_index(drop=True), left_out


def campaign_config(campaign: Campaign) -> CalibrationConfig:
    """The campaign's ``[calibration]`` block resolved (defaults without one)."""
    return parse_calibration_block(campaign.calibration or {}, source=str(campaign.path),
                                   line_of=campaign.line_of)


def campaign_observations(campaign: Campaign, observations: ObservationsInput = None, *,
                          outdir: str | Path | None = None) -> pd.DataFrame:
    """The observations table of ``campaign``.

    Parameters
    ----------
    campaign : Campaign
    observations : DataFrame, Observations, str, pathlib.Path or None
        A table, ``observe_campaign``'s result, the path of a table written by
        ``rigtools observe``, or None: observe the campaign now.
    outdir : str or pathlib.Path, optional
        Where a table observed here is written (``observations.parquet``).
    """
    from rigtools.campaign.observation_files import read_observations, write_observations

    if isinstance(observations, pd.DataFrame):
        return observations
    if isinstance(observations, Observations):
        return observations.table
    if observations is not None:
        return read_observations(observations)
    from rigtools.campaign.observe import observe_campaign

    obs = observe_campaign(campaign)
    if outdir is not None:
        Path(outdir).mkdir(parents=True, exist_ok=True)
        write_observations(obs, Path(outdir) / "observations.parquet")
    return obs.table


def calibrate(
    campaign: Campaign | str | Path,
    observations: ObservationsInput = None,
    *,
    config: CalibrationConfig | None = None,
    outdir: str | Path | None = None,
    progress: Callable[[int, int, float | None], None] | None = None,
    seed: int | None = None,
) -> CalibrationResult:
    """Calibrate a campaign: backlash, thermal closure, critical gaps, margins and regimes.

    Parameters
    ----------
    campaign : Campaign, str or pathlib.Path
        The loaded campaign or its manifest (TOML).
    observations : DataFrame, Observations, str, pathlib.Path or None
        See :func:`campaign_observations` (None: observe the campaign first; the table is
        written into ``outdir`` when one is given).
    config : CalibrationConfig, optional
        Instead of the campaign's ``[calibration]`` block.
    outdir, progress, seed
        As :func:`~rigtools.calibration.api.calibrate_observations` (``outdir`` holds the
        checkpoint a killed run resumes from; outputs are written by
        :func:`~rigtools.calibration.write_outputs`).

    Returns
    -------
    CalibrationResult

    Raises
    ------
    CampaignError
        The manifest or its ``[calibration]`` / ``[thermal]`` block is wrong (file and line).
    CalibrationError
        No usable run, priors that exclude the data, every run jammed (run or key named).

    Notes
    -----
    Runs on another gear set than the campaign's are left out (:func:`campaign_gear_rows`);
    each is named in the result's ``warnings`` (and the summary's).
    """
    camp = campaign if isinstance(campaign, Campaign) else load_campaign(campaign)
    cfg = campaign_config(camp) if config is None else config
    table, left_out = campaign_gear_rows(camp, campaign_observations(camp, observations,
                                                                     outdir=outdir))
    result = calibrate_observations(table, camp.gear.pair, cfg,
                                    thermal_reference=campaign_reference(camp), outdir=outdir,
                                    progress=progress, seed=seed)
    if not left_out:
        return result
    notes = [f"run {r!r} left out: {why}" for r, why in left_out.items()]
    summary = {**result.summary, "warnings": [*notes, *result.summary.get("warnings", [])]}
    return replace(result, warnings=(*notes, *result.warnings), summary=summary)

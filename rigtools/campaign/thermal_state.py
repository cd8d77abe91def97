"""The campaign's ``[thermal]`` block as :mod:`models.thermal`'s reference state.

The manifest states the thermal reference once for the whole campaign
(:class:`~rigtools.campaign.manifest.Thermal`: the temperature the backlash is stated at, and
whether the housing keeps the centre distance or follows the oil); the physics takes it as a
:class:`models.thermal.reference_state.ThermalReference`, which for a housing that follows the
oil also needs that run's oil temperature. :func:`thermal_reference` is the one place the
first becomes the second, so every stage (observations, calibration, report) reads the block
the same way (SEED-NOTES 8).

Errors::

    RigtoolsError
    └── CampaignError (ValueError)     the block lacks what the reference state needs, or the
                                       physics refuses it (names the file and the line)
"""

from __future__ import annotations

from models.errors import ModelError
from models.thermal.reference_state import ThermalReference
from rigtools.campaign.manifest import Campaign
from rigtools.errors import CampaignError

__all__ = ["thermal_reference"]


def thermal_reference(campaign: Campaign, *, oil_temperature_C: float | None = None
                      ) -> ThermalReference:
    """The thermal reference state of a campaign (for one run, when the housing follows the oil).

    Parameters
    ----------
    campaign : Campaign
        The loaded campaign; its ``thermal`` block is read.
    oil_temperature_C : float, optional
        The run's oil temperature (deg C), e.g. its resolved ``oil_temperature_C`` condition.
        Required when ``housing = "follows-oil"``; not used otherwise.

    Returns
    -------
    models.thermal.reference_state.ThermalReference
        ``reference_temperature_C`` and ``housing`` as the block states them; a block without
        ``housing`` takes the model's default, ``"fixed-centre-distance"``. The flash
        temperature and the housing's expansion coefficient keep the model's defaults (the
        manifest has no keys for them yet).

    Raises
    ------
    CampaignError
        When the campaign has no ``reference_temperature_C`` (the model has no default for
        it: every thermal deformation counts from it), or when the model refuses the state
        (``housing = "follows-oil"`` without an oil temperature), naming the campaign file and
        the ``[thermal]`` line.

    Examples
    --------
    >>> from pathlib import Path
    >>> from rigtools.campaign.manifest import AnalysisSettings, Sensors, Thermal
    >>> from models.geometry import load_gear_set
    >>> c = Campaign("study", "fzg-c", "", load_gear_set("fzg-c"), Sensors(),
    ...              Thermal(20.0, "follows-oil"), AnalysisSettings(), (), Path("c.toml"))
    >>> ref = thermal_reference(c, oil_temperature_C=90.0)
    >>> ref.reference_temperature_C, ref.housing, ref.oil_temperature_C
    (20.0, 'follows-oil', 90.0)
    """
    th = campaign.thermal
    where = f"line {th.line}" if th.line is not None else None
    if th.reference_temperature_C is None:
        raise CampaignError(campaign.path, where,
                            "key 'reference_temperature_C' in [thermal] (the temperature the "
                            "backlash is stated at, deg C)", "none")
    try:
        if th.housing is None:  # the model's default housing
            return ThermalReference(th.reference_temperature_C,
                                    oil_temperature_C=oil_temperature_C)
        return ThermalReference(th.reference_temperature_C, th.housing,
                                oil_temperature_C=oil_temperature_C)
    except ModelError as exc:
        raise CampaignError(campaign.path, where, "a [thermal] block the thermal model accepts",
                            None, str(exc)) from exc

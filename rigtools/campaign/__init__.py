"""The campaign stage: the manifest, observing a campaign, and the observations table.

A *campaign* is the user's one description of an experiment (a TOML manifest listing runs and
their conditions, the gear set, the sensor mapping and the thermal reference state); this
package reads it and turns it into the one tidy table the later stages read:

- :mod:`~rigtools.campaign.manifest`: :func:`load_campaign` validates the file once, at the
  boundary, into a :class:`Campaign` (contract: ``data_schemas/campaign.schema.json``), with
  :mod:`~rigtools.campaign.run_files` (run files by glob) and
  :mod:`~rigtools.campaign.conditions_sheet` (conditions from a CSV sheet) and
  :mod:`~rigtools.campaign.key_lines` (errors that name a key and its line);
- :mod:`~rigtools.campaign.thermal_state`: :func:`thermal_reference`, the ``[thermal]``
  block as :mod:`models.thermal`'s reference state;
- :mod:`~rigtools.campaign.observe`: :func:`observe_campaign` reads and analyses every run
  (:mod:`rigtools.ingest`, :mod:`rigtools.analysis`) into :class:`Observations`; per run,
  :func:`read_run` reads the recording with the run's sensors and :func:`observe_recording`
  analyses it (:func:`observe_run` does both); the Arms rows in
  :mod:`~rigtools.campaign.observe_orders`;
- :mod:`~rigtools.campaign.observation_table`: the table's columns, flags and result classes;
- :mod:`~rigtools.campaign.observation_files`: the table as Parquet (write, read, validate).

:func:`observe_campaign`, :func:`observe_run`, :func:`read_run`, :func:`observe_recording`
and :func:`thermal_reference` are imported on
first use: reading a campaign or an observations table does not load the signal analysis
(scipy.signal) or the thermal physics.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rigtools.campaign.manifest import (
    CONDITION_KEYS,
    SENSOR_OVERRIDES,
    AnalysisSettings,
    Campaign,
    CampaignRun,
    Sensors,
    Thermal,
    load_campaign,
)
from rigtools.campaign.observation_files import (
    read_observations,
    validate_observations,
    write_observations,
)
from rigtools.campaign.observation_table import (
    FLAGS,
    Observations,
    RunObservations,
    observation_columns,
    to_frame,
)
from rigtools.errors import CampaignError
from rigtools.lazy_exports import lazy_exports

if TYPE_CHECKING:
    from rigtools.campaign.observe import (
        observe_campaign,
        observe_recording,
        observe_run,
        read_run,
    )
    from rigtools.campaign.thermal_state import thermal_reference

__all__ = [
    "CONDITION_KEYS",
    "FLAGS",
    "SENSOR_OVERRIDES",
    "AnalysisSettings",
    "Campaign",
    "CampaignError",
    "CampaignRun",
    "Observations",
    "RunObservations",
    "Sensors",
    "Thermal",
    "load_campaign",
    "observation_columns",
    "observe_campaign",
    "observe_recording",
    "observe_run",
    "read_observations",
    "read_run",
    "thermal_reference",
    "to_frame",
    "validate_observations",
    "write_observations",
]

#: Names whose modules load the signal analysis or the physics, imported on first access.
_ON_FIRST_USE = {
    "observe_campaign": "rigtools.campaign.observe",
    "observe_recording": "rigtools.campaign.observe",
    "observe_run": "rigtools.campaign.observe",
    "read_run": "rigtools.campaign.observe",
    "thermal_reference": "rigtools.campaign.thermal_state",
}


__getattr__, __dir__ = lazy_exports(__name__, globals(), _ON_FIRST_USE, __all__)

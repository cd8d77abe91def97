"""Ingest: CAN logs (BLF, ASC, TRC, candump, CSV + DBC) and MCAP files into one Recording."""

from rigtools.ingest.layout import ChannelMapping, load_mapping
from rigtools.ingest.losses import FrameGap, LossTally, loss_tally
from rigtools.ingest.parquet import read_parquet, write_parquet
from rigtools.ingest.reader import read
from rigtools.ingest.recording import (
    Channel,
    Gap,
    IngestReport,
    Provenance,
    Recording,
    RunMetadata,
    SlowSignal,
)
from rigtools.ingest.registry import detect_format

__all__ = [
    "Channel",
    "ChannelMapping",
    "FrameGap",
    "Gap",
    "IngestReport",
    "LossTally",
    "Provenance",
    "Recording",
    "RunMetadata",
    "SlowSignal",
    "detect_format",
    "load_mapping",
    "loss_tally",
    "read",
    "read_parquet",
    "write_parquet",
]

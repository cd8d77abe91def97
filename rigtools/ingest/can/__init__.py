"""CAN log readers: each log format parsed into frame batches, decoded through a DBC.

=============================================  ===================================================
module                                         what it holds
=============================================  ===================================================
:mod:`~rigtools.ingest.can.frames`             :class:`CanFrameBatch`, the columnar frames every
                                               format yields
:mod:`~rigtools.ingest.can.blf`                Vector BLF (containers, ``blf_objects``: the log
                                               objects)
:mod:`~rigtools.ingest.can.candump`            candump ``-L`` logs
:mod:`~rigtools.ingest.can.asc`                Vector ASC (python-can's parser)
:mod:`~rigtools.ingest.can.trc`                PEAK TRC (python-can's parser)
:mod:`~rigtools.ingest.can.csv_log`            python-can CSV (python-can's parser)
:mod:`~rigtools.ingest.can.textlog`            what the text logs share: lines, encodings,
                                               every line accounted for
:mod:`~rigtools.ingest.can.dbc`                the DBC loaded, signals decoded over whole
                                               batches
:mod:`~rigtools.ingest.can.assembly`           decoded frames to channels and slow signals
:mod:`~rigtools.ingest.can.reader`             :class:`CanLogReader`: a format's entry in the
                                               registry, the DBC decoding shared
=============================================  ===================================================

Each format module states ``NAME``, ``sniff``, ``iter_batches`` and its ``READER``; the
registry (:data:`rigtools.ingest.registry.CAN_READERS`) lists them.
"""

from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.can.reader import CanLogReader

__all__ = ["CanFrameBatch", "CanLogReader"]

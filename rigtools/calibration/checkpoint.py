"""Chain storage that survives SIGKILL: emcee's ``HDFBackend`` committing at checkpoints.

:class:`emcee.backends.HDFBackend` opens the HDF5 file for every step (about 10 ms a step on
the reference machine, more than the model), and writes the chain, the acceptance counts, the
random state and the iteration counter one after the other, so a kill between two of those
writes leaves a file whose random state belongs to another step than its chain. For a resume
that gives the same numbers as an uninterrupted run, :class:`CheckpointBackend` (a subclass;
the file layout stays emcee's, readable by ``HDFBackend``):

* buffers steps in memory and writes them at :meth:`CheckpointBackend.commit` (the sampler
  driver commits at every convergence check), one file open per commit;
* writes the rows first, then the random state, acceptance counts and the driver's own
  checkpoint data into one of two alternating *slots* tagged with their iteration, and the
  iteration counter last. A kill at any point leaves the counter at the previous commit and
  that commit's slot intact, so the file always resumes from a consistent state (rows beyond
  the counter are ignored and overwritten);
* stores a fingerprint of the configuration and data: a file written for another campaign or
  setting is never resumed.

If HDF5 itself cannot open a file damaged by a kill in the middle of a write (its metadata is
not journalled), :func:`open_checkpoint` reports it and the driver starts the chain over from
the seed, so the numbers are the same either way; only the time is lost.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from emcee.backends import HDFBackend

__all__ = ["CheckpointBackend", "open_checkpoint"]


class CheckpointBackend(HDFBackend):
    """emcee ``HDFBackend`` that buffers steps and commits them atomically (module notes).

    Parameters
    ----------
    filename : str or pathlib.Path
        The HDF5 file (created when absent).
    name : str
        Group of this chain in the file (one per model variant).
    fingerprint : str
        Identity of the configuration and data the chain belongs to.
    """

    def __init__(self, filename: str | Path, name: str, fingerprint: str) -> None:
        super().__init__(str(filename), name=name)
        self.fingerprint = fingerprint
        self._buffer: list[tuple[np.ndarray, np.ndarray, np.ndarray, Any]] = []

    # -- state on disk ----------------------------------------------------------------------
    @property
    def committed_iteration(self) -> int:
        """Steps on disk (the last commit)."""
        with self.open() as f:
            return int(f[self.name].attrs["iteration"])

    @property
    def iteration(self) -> int:
        """Steps taken: on disk plus buffered."""
        return self.committed_iteration + len(self._buffer)

    def _slot(self, g: h5py.Group) -> str | None:
        it = int(g.attrs["iteration"])
        for k in ("slot0", "slot1"):
            if f"{k}_iteration" in g.attrs and int(g.attrs[f"{k}_iteration"]) == it:
                return k
        return None

    @property
    def random_state(self) -> Any:
        """The sampler's random state after the last committed step (None before any)."""
        with self.open() as f:
            g = f[self.name]
            k = self._slot(g)
            if k is None:
                return None
            return tuple(g.attrs[f"{k}_random_state_{i}"] for i in range(5))

    @property
    def accepted(self) -> np.ndarray:
        """Accepted proposals per walker up to the last commit (buffered steps included)."""
        with self.open() as f:
            g = f[self.name]
            k = self._slot(g)
            base = (np.zeros(int(g.attrs["nwalkers"])) if k is None
                    else np.array(g.attrs[f"{k}_accepted"], dtype=float))
        for _, _, acc, _ in self._buffer:
            base = base + acc
        return base

    def checkpoint_data(self) -> dict[str, Any]:
        """The driver's data stored with the last commit (empty before any)."""
        with self.open() as f:
            g = f[self.name]
            k = self._slot(g)
            if k is None:
                return {}
            return dict(json.loads(str(g.attrs[f"{k}_data"])))

    # -- emcee's backend interface ------------------------------------------------------------
    def reset(self, nwalkers: int, ndim: int) -> None:
        """Start an empty chain (emcee's layout) tagged with the fingerprint."""
        self._buffer.clear()
        super().reset(nwalkers, ndim)
        with self.open("a") as f:
            g = f[self.name]
            g.attrs["rigtools_fingerprint"] = self.fingerprint
            g.attrs["commits"] = 0

    def grow(self, ngrow: int, blobs: Any) -> None:
        """Nothing to do: rows are allocated at commit (blobs are not supported)."""
        if blobs is not None:
            raise ValueError("CheckpointBackend does not store blobs")

    def save_step(self, state: Any, accepted: np.ndarray) -> None:
        """Buffer one step (written by :meth:`commit`)."""
        self._buffer.append((np.array(state.coords, dtype=float),
                             np.array(state.log_prob, dtype=float),
                             np.asarray(accepted, dtype=float).copy(), state.random_state))

    def get_value(self, name: str, flat: bool = False, thin: int = 1,
                  discard: int = 0) -> Any:
        """As emcee's, over committed and buffered steps (commits first)."""
        if self._buffer:
            raise RuntimeError("commit() the buffered steps before reading the chain")
        return super().get_value(name, flat=flat, thin=thin, discard=discard)

    def buffered(self) -> tuple[np.ndarray, np.ndarray]:
        """The buffered (not yet committed) steps: chain ``(n, W, D)``, log prob ``(n, W)``."""
        if not self._buffer:
            nw, nd = self.shape
            return np.empty((0, nw, nd)), np.empty((0, nw))
        return (np.stack([b[0] for b in self._buffer]),
                np.stack([b[1] for b in self._buffer]))

    def commit(self, data: dict[str, Any] | None = None) -> None:
        """Write the buffered steps and ``data`` (JSON-ready) as one checkpoint (module notes)."""
        with self.open("a") as f:
            g = f[self.name]
            it = int(g.attrs["iteration"])
            n = len(self._buffer)
            if n:
                for key in ("chain", "log_prob"):
                    if g[key].shape[0] < it + n:
                        g[key].resize(it + n, axis=0)
                g["chain"][it:it + n] = np.stack([b[0] for b in self._buffer])
                g["log_prob"][it:it + n] = np.stack([b[1] for b in self._buffer])
            old = self._slot(g)
            acc = (np.zeros(int(g.attrs["nwalkers"])) if old is None
                   else np.array(g.attrs[f"{old}_accepted"], dtype=float))
            for _, _, a, _ in self._buffer:
                acc = acc + a
            commits = int(g.attrs["commits"])
            k = f"slot{commits % 2}"
            if n:
                state = self._buffer[-1][3]
                for i, v in enumerate(state):
                    g.attrs[f"{k}_random_state_{i}"] = v
            elif old is not None:
                for i in range(5):
                    g.attrs[f"{k}_random_state_{i}"] = g.attrs[f"{old}_random_state_{i}"]
            g.attrs[f"{k}_accepted"] = acc
            g.attrs[f"{k}_data"] = json.dumps(data or {})
            g.attrs[f"{k}_iteration"] = it + n
            g["accepted"][:] = acc
            f.flush()
            g.attrs["iteration"] = it + n
            g.attrs["commits"] = commits + 1
        self._buffer.clear()


def open_checkpoint(path: str | Path, name: str, fingerprint: str, nwalkers: int,
                    ndim: int) -> tuple[CheckpointBackend, int, str | None]:
    """Open (or create) the checkpoint of one chain, ready to resume or start.

    Parameters
    ----------
    path : str or pathlib.Path
        The HDF5 file.
    name : str
        The chain's group.
    fingerprint : str
        Identity of configuration and data.
    nwalkers, ndim : int
        Shape of the ensemble.

    Returns
    -------
    backend : CheckpointBackend
    iteration : int
        Committed steps that will be resumed (0: a fresh chain).
    note : str or None
        Why an existing chain was not resumed, when it was not.
    """
    p = Path(path)
    backend = CheckpointBackend(p, name, fingerprint)
    note = None
    if p.exists():
        try:
            with h5py.File(p, "r") as f:
                if name in f:
                    g = f[name]
                    same = (str(g.attrs.get("rigtools_fingerprint", "")) == fingerprint
                            and int(g.attrs["nwalkers"]) == nwalkers
                            and int(g.attrs["ndim"]) == ndim)
                    it = int(g.attrs["iteration"])
                    if same and it > 0 and backend._slot(g) is not None:
                        return backend, it, None
                    if not same:
                        note = (f"the checkpoint {p.name}:{name} belongs to another "
                                "configuration or data; the chain starts over")
        except (OSError, KeyError, ValueError) as exc:
            note = (f"the checkpoint {p.name} cannot be read ({exc}); the chain starts "
                    "over from the seed")
            os.remove(p)
    backend.reset(nwalkers, ndim)
    return backend, 0, note

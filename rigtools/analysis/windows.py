r"""Gap-aware segmenting: split a channel at its gaps, never bridge them.

A channel's ``valid`` mask (``False`` in gaps and for rejected samples) cuts the samples into
*valid segments*, the maximal runs of consecutive valid samples. Spectral estimators work on
each segment separately, so that no analysis window straddles a gap and nothing is bridged or
interpolated. A segment shorter than one analysis window (``min_length``) is dropped; both the
segments and the samples dropped are counted, so the loss shows up in the result.

The number of Welch windows that fit a segment of length ``L`` is

.. math:: K(L) = \lfloor (L - n_\text{overlap}) / (n_\text{perseg} - n_\text{overlap})
          \rfloor \quad (L \ge n_\text{perseg}),

the count :func:`scipy.signal.welch` uses (it drops the tail that does not fill a window).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Segments", "n_windows", "true_runs", "valid_segments"]


@dataclass(frozen=True)
class Segments:
    """The valid segments of a channel and what was dropped.

    Attributes
    ----------
    starts, stops : numpy.ndarray
        int64, shape ``(n_kept,)``: the kept segments are ``x[starts[i]:stops[i]]``, in order.
    n_found : int
        Valid segments found (kept and dropped).
    n_dropped : int
        Segments shorter than ``min_length``, dropped.
    n_samples_dropped : int
        Valid samples in the dropped segments.
    n_invalid : int
        Samples with ``valid == False``.
    n_samples : int
        Length of the mask.
    min_length : int
        Shortest segment kept (samples).
    """

    starts: np.ndarray
    stops: np.ndarray
    n_found: int
    n_dropped: int
    n_samples_dropped: int
    n_invalid: int
    n_samples: int
    min_length: int

    @property
    def n_kept(self) -> int:
        """Segments kept."""
        return int(self.starts.size)

    @property
    def lengths(self) -> np.ndarray:
        """Lengths of the kept segments (samples)."""
        return self.stops - self.starts

    @property
    def n_samples_kept(self) -> int:
        """Valid samples in the kept segments."""
        return int(np.sum(self.lengths))

    @property
    def is_whole(self) -> bool:
        """True when there is one kept segment covering every sample (no gap at all)."""
        return (self.n_kept == 1 and int(self.starts[0]) == 0
                and int(self.stops[0]) == self.n_samples)

    def n_windows(self, nperseg: int, noverlap: int) -> int:
        """Welch windows over all kept segments (see :func:`n_windows`)."""
        return int(np.sum(n_windows(self.lengths, nperseg, noverlap)))

    def slices(self) -> list[slice]:
        """The kept segments as slices."""
        return [slice(int(a), int(b)) for a, b in zip(self.starts, self.stops, strict=True)]


def n_windows(length: int | np.ndarray, nperseg: int, noverlap: int) -> np.ndarray:
    """Number of Welch windows that fit in segments of ``length`` samples.

    Parameters
    ----------
    length : int or numpy.ndarray
        Segment length(s) (samples).
    nperseg : int
        Window length (samples).
    noverlap : int
        Overlap of consecutive windows (samples), ``0 <= noverlap < nperseg``.

    Returns
    -------
    numpy.ndarray
        int64, same shape as ``length``; 0 where ``length < nperseg``.

    Examples
    --------
    >>> int(n_windows(4096 * 4, 4096, 2048))
    7
    """
    length = np.asarray(length, dtype=np.int64)
    step = nperseg - noverlap
    k = (length - noverlap) // step
    return np.where(length >= nperseg, k, 0).astype(np.int64)


def valid_segments(valid: np.ndarray, min_length: int = 1) -> Segments:
    """Split a validity mask into runs of valid samples; drop and count the short ones.

    Parameters
    ----------
    valid : numpy.ndarray
        Boolean mask, shape ``(n,)``: ``True`` where the sample is usable.
    min_length : int
        Shortest segment kept (samples), e.g. the analysis window length ``nperseg``.

    Returns
    -------
    Segments

    Examples
    --------
    >>> s = valid_segments(np.array([1, 1, 1, 0, 1, 0, 1, 1], bool), min_length=2)
    >>> s.slices(), s.n_dropped, s.n_samples_dropped, s.n_invalid
    ([slice(0, 3, None), slice(6, 8, None)], 1, 1, 2)
    """
    v = np.asarray(valid)
    if v.ndim != 1:
        raise ValueError(f"`valid` must be 1-D, was {v.ndim}-D with shape {v.shape}")
    if v.dtype != np.bool_:
        v = v.astype(bool)
    n = int(v.size)
    if min_length < 1:
        raise ValueError(f"`min_length` must be >= 1, was {min_length}")
    if n and v.all():  # fast path: no gap
        starts = np.array([0], np.int64)
        stops = np.array([n], np.int64)
        n_invalid = 0
    else:
        edges = np.diff(v.view(np.int8), prepend=np.int8(0), append=np.int8(0))
        starts = np.flatnonzero(edges == 1).astype(np.int64)
        stops = np.flatnonzero(edges == -1).astype(np.int64)
        n_invalid = n - int(np.sum(stops - starts))
    lengths = stops - starts
    keep = lengths >= min_length
    return Segments(
        starts=starts[keep],
        stops=stops[keep],
        n_found=int(starts.size),
        n_dropped=int(np.count_nonzero(~keep)),
        n_samples_dropped=int(np.sum(lengths[~keep])),
        n_invalid=n_invalid,
        n_samples=n,
        min_length=int(min_length),
    )


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index ranges ``[a, b)`` of consecutive ``True`` in ``mask``.

    Examples
    --------
    >>> true_runs(np.array([1, 1, 0, 1], bool))
    [(0, 2), (3, 4)]
    """
    m = np.r_[False, mask, False].astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    stops = np.flatnonzero(d == -1)
    return list(zip(starts.tolist(), stops.tolist(), strict=True))

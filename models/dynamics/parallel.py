r"""Independent frequency sweeps run in parallel (numba ``prange``) over parameter sets.

A study of seed 003 (Figs. 8-11) is many sweeps of the same kind: several torques, damping
ratios, backlash values or tip reliefs, each swept up and down. :func:`sweep_many` runs them
all in one compiled call, one sweep per thread-chunk (``numba.prange`` over the sweeps; the
points of a sweep stay sequential because each starts from the previous one's state). Each
sweep is computed by the very kernel that :func:`models.dynamics.sweep.sweep` uses
(:func:`~models.dynamics.sdof_kernels.sweep_kernel`), on the same tables, so its results are
identical to the serial sweep's (tested bit for bit). Models with fewer tooth-pair columns than
the widest are padded with inert columns (zero stiffness, infinite offsets), which changes no
floating-point operation.

The compiled kernel lives in :mod:`models.dynamics.sdof_kernels` next to the per-sweep kernel, so
numba's on-disk cache of both is invalidated together when that file changes. Threads: numba's
default (the number of cores); set ``NUMBA_NUM_THREADS`` or call
``numba.set_num_threads`` to change it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from models.dynamics.integrate import model_tables
from models.dynamics.sdof import DynamicModel
from models.dynamics.sdof_kernels import sweep_many_kernel
from models.dynamics.sweep import SweepResult, empty_outputs, result_from_outputs

__all__ = ["SweepJob", "sweep_many"]

Direction = Literal["up", "down"]


@dataclass(frozen=True)
class SweepJob:
    """Which sweep a result of :func:`sweep_many` is.

    Attributes
    ----------
    model_index : int
        Index into ``models``.
    direction : str
        ``"up"`` or ``"down"``.
    """

    model_index: int
    direction: str


def sweep_many(
    models: Sequence[DynamicModel],
    frequencies: ArrayLike,
    *,
    directions: Sequence[Direction] = ("up", "down"),
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
    record_periods: int = 4,
) -> tuple[list[SweepResult], list[SweepJob]]:
    """Sweep every model in every direction, in parallel; each sweep as :func:`sweep` would.

    Parameters
    ----------
    models : sequence of SDOFModel or ITMSModel
        The parameter sets (e.g. one per torque, damping ratio or backlash).
    frequencies : array_like
        ``Lambda`` grid (-), ``(M,)`` for all models or ``(len(models), M)``; sorted upwards
        here, ``"down"`` runs it reversed.
    directions : sequence of {"up", "down"}
        Directions run for every model.
    steps_per_period, tol, min_periods, max_periods, record_periods
        As for :func:`~models.dynamics.sweep.sweep`.

    Returns
    -------
    results : list of SweepResult
        In job order (model-major); a ``"down"`` result is in sweep order (decreasing
        ``Lambda``), exactly :func:`sweep` of the reversed grid; use ``.sorted()`` to compare
        point by point.
    jobs : list of SweepJob
        ``(model_index, direction)`` of each result.

    Examples
    --------
    >>> from models.dynamics import SDOFModel
    >>> from models.stiffness.mesh_cycle import Harmonics
    >>> ms = [SDOFModel(zeta=z, force=0.0, backlash=0.0,
    ...                 error=Harmonics(0.0, np.array([0.1]), np.array([0.0])))
    ...       for z in (0.05, 0.1)]
    >>> res, jobs = sweep_many(ms, [0.5, 1.0], directions=("up",), tol=1e-9, max_periods=4000)
    >>> [round(float(r.arms[1]), 3) for r in res]  # 0.1 / (2 zeta) at Lambda = 1
    [1.0, 0.5]
    """
    if len(models) == 0:
        raise ValueError("`models` must not be empty")
    for d in directions:
        if d not in ("up", "down"):
            raise ValueError(f"`directions` must hold 'up' or 'down', had {d!r}")
    if not tol >= 0 or not 0 <= min_periods <= max_periods or record_periods < 1:
        raise ValueError("need tol >= 0, 0 <= min_periods <= max_periods, record_periods >= 1")
    f = np.asarray(frequencies, dtype=float)
    if f.ndim == 1:
        f = np.broadcast_to(f, (len(models), f.size))
    if f.ndim != 2 or f.shape[0] != len(models):
        raise ValueError(
            f"`frequencies` must be (M,) or (len(models)={len(models)}, M), "
            f"was {np.shape(frequencies)}"
        )
    if not (np.all(np.isfinite(f)) and np.all(f > 0)):
        raise ValueError("`frequencies` must be finite and > 0")
    f = np.sort(f, axis=1)
    tables = [model_tables(m, steps_per_period) for m in models]
    jobs = [SweepJob(i, d) for i in range(len(models)) for d in directions]
    n_jobs, n2 = len(jobs), 2 * int(steps_per_period)
    width = max(t.kd.shape[1] for t in tables)
    kd = np.zeros((n_jobs, n2, width))
    kb = np.zeros((n_jobs, n2, width))
    ed = np.full((n_jobs, n2, width), np.inf)
    eb = np.full((n_jobs, n2, width), -np.inf)
    doff = np.empty((n_jobs, n2))
    boff = np.empty((n_jobs, n2))
    npair = np.zeros((n_jobs, n2), dtype=np.int64)
    freqs = np.empty((n_jobs, f.shape[1]))
    x0, v0 = np.empty(n_jobs), np.zeros(n_jobs)
    zeta, force, b = np.empty(n_jobs), np.empty(n_jobs), np.empty(n_jobs)
    for s, job in enumerate(jobs):
        i, t, m = job.model_index, tables[job.model_index], models[job.model_index]
        p = t.kd.shape[1]
        kd[s, :, :p], ed[s, :, :p], kb[s, :, :p], eb[s, :, :p] = t.kd, t.ed, t.kb, t.eb
        doff[s], boff[s], npair[s] = t.drive_offset, t.back_offset, t.static_pairs
        freqs[s] = f[i] if job.direction == "up" else f[i, ::-1]
        x0[s] = m.start_dte()
        zeta[s], force[s], b[s] = m.zeta, m.force, m.backlash
    out = empty_outputs((n_jobs, f.shape[1]))
    cs, sn = tables[0].cos, tables[0].sin
    sweep_many_kernel(
        x0,
        v0,
        zeta,
        force,
        b,
        kd,
        ed,
        kb,
        eb,
        doff,
        boff,
        npair,
        cs,
        sn,
        freqs,
        float(tol),
        int(min_periods),
        int(max_periods),
        int(record_periods),
        out["amps"],
        out["mean"],
        out["loss"],
        out["impact"],
        out["partial"],
        out["periods_run"],
        out["period"],
        out["poinc"],
        out["entry"],
    )
    results = [
        result_from_outputs(
            freqs[s].copy(),
            {k: v[s].copy() for k, v in out.items()},
            models[job.model_index].length_scale_m,
        )
        for s, job in enumerate(jobs)
    ]
    return results, jobs

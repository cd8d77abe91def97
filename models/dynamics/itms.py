r"""Individual tooth mesh stiffness (ITMS) model: one spring per tooth pair (seed 003 Eq. 28).

Seed 003 Eq. 28 (after Liu and Parker) divides the mesh force among the tooth pairs:

.. math:: \ddot x + 2 \zeta \dot x + \sum_j \tilde k_j(\tau)\, f_j(x) = \tilde F

with, per pair ``j``, the non-dimensional stiffness ``tilde k_j = K_j / k_0`` (``K_j = 1 / C(s_j)``,
the tooth-pair compliance of :mod:`models.stiffness`) and the contact function ``f_j``. What
the seed prints as ``h_j k_j (x - e_j)`` is replaced by the dead zone (SEED-NOTES 16), and the
pair's drive-side *gap* is its profile error plus its corner-contact separation distance,
``g_j = e(s_j) + S(s_j)`` (exactly the gap of the static analysis,
:func:`~models.stiffness.mesh_cycle.mesh_cycle`), so that a pair touches only while its own
``x - b > g_j``:

.. math::

    f_j(x) = \max(x - \tilde b - \tilde g_j, 0)
             + \chi_j \min(x + \tilde b - \tilde e_{b,j}, 0)

* drive side: corner contact and tip relief enter through ``g_j``; a pair that cannot touch
  (infinite separation) has ``K_j = 0``;
* back side (``chi_j = 1`` on the theoretical path AE only, no corner contact): the seed gives
  no back-side geometry, so the back-side offset ``e_b`` is a choice (``back_flank``,
  :func:`~models.dynamics.back_flank.back_flank_offset`): ``"unmodified"`` (default) perfect back
  involutes, ``e_b = 0`` -- the relief of the mesh cycle is ground on the drive flanks;
  ``"mirror"`` the same relief on the back flanks, ``e_b = -e_j`` (a relieved back flank
  touches at ``x < -b - e_j``, later, as a relieved drive flank does); ``"seed"`` Eq. 28
  literally, ``e_b = +e_j``, the displacement-error convention in which drive-flank relief
  *narrows* the back gap (with ``Delta = 1`` back contact then starts at ``x = -0.62 b``
  instead of ``-b``). The back flanks are taken at the drive-side roll positions with the
  drive-side pair compliance: the back-side line of action of a symmetric spur pair carries
  the same sequence of pair stiffnesses, shifted in phase, which this SDOF model does not
  resolve (as Kahraman-Singh, one stiffness curve for both sides).

Consequences (tested): the quasi-static solution is the LSTE of the static analysis,
``x - b = x_s(tau) / L`` at every phase; with a common error ``e`` for all pairs and no corner
contact it *is* the FVMS model of the same back flank (``error="cycle"``; Eq. 26, ``k_F f(x -
e)`` for ``"seed"``), because the sum of the pair springs is ``k_F``. Partial contact loss
(some pairs separate, others still touch) is what this model adds over the FVMS, VVMS and LSTE
models; sweeps report it as the fraction of the record
(:attr:`~models.dynamics.sweep.SweepResult.partial_contact_loss`).

Scaling: ``k_0`` is the mean FVMS (Eq. 27, ``k_F0``), ``L`` the half backlash by default,
``tilde F = F / (k_0 L)``. The per-pair curves are those of a :class:`MeshCycle`, stitched into
the passage of one tooth pair (:meth:`~models.stiffness.mesh_cycle.MeshCycle.tooth_pair_history`
order) and interpolated linearly in the passage coordinate ``sigma = (s - A) / p_b``.

References
----------
.. [1] W. Yu, C. K. Mechefske, Mech. Mach. Theory 96 (2016) 146-164, Sec. 3.1, Eq. 28.
.. [2] G. Liu, R. G. Parker, "Dynamic modeling and analysis of tooth profile modification for
   multimesh gear vibration", ASME J. Mech. Des. 130 (2008) 121402.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from models.dynamics.back_flank import BackFlank, back_flank_offset
from models.errors import ModelError
from models.stiffness.mesh_cycle import MeshCycle

__all__ = ["ITMSModel", "itms_from_mesh_cycle"]


@dataclass(frozen=True)
class ITMSModel:
    """Non-dimensional ITMS model (seed 003 Eq. 28, dead-zone contact per pair).

    Attributes
    ----------
    zeta : float
        Damping ratio (-).
    force : float
        ``tilde F = F / (k_0 L)`` (-).
    backlash : float
        ``tilde b = b / L`` (-).
    passage : numpy.ndarray
        Passage coordinate ``sigma = (s - A) / p_b`` of the samples (-), increasing, uniform.
    drive_stiffness, drive_gap, back_stiffness, back_error : numpy.ndarray
        Per sample of the passage: ``K / k_0`` (0 where the pair cannot touch), ``g / L``,
        ``K / k_0`` on AE (else 0), the back-side offset ``e_b / L`` (-).
    slot_offsets : numpy.ndarray
        The slots ``m``: at cycle phase ``tau`` the pairs sit at ``sigma = tau + m``.
    length_scale_m : float
        ``L`` (m).
    mean_stiffness_N_m : float
        ``k_0``, the mean FVMS (N/m).
    kind : str
        ``"itms"``.
    """

    zeta: float
    force: float
    backlash: float
    passage: np.ndarray
    drive_stiffness: np.ndarray
    drive_gap: np.ndarray
    back_stiffness: np.ndarray
    back_error: np.ndarray
    slot_offsets: np.ndarray
    length_scale_m: float
    mean_stiffness_N_m: float
    kind: str = "itms"

    def __post_init__(self) -> None:
        if not (self.zeta >= 0 and self.backlash >= 0):
            raise ModelError("ITMSModel needs zeta >= 0 and backlash >= 0")

    def _at(self, phase: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        sig = np.asarray(phase, dtype=float)[..., None] + self.slot_offsets
        return tuple(  # type: ignore[return-value]
            np.interp(sig, self.passage, c)
            for c in (self.drive_stiffness, self.drive_gap, self.back_stiffness, self.back_error)
        )

    def pair_tables(
        self, steps_per_period: int
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(kd, ed, kb, eb)`` at the ``2 N`` half steps, one column per slot.

        ``ed = b``-free drive offset ``g_j`` (the kernel adds ``b``), ``eb`` the back offset.
        """
        phase = np.arange(2 * steps_per_period) / (2 * steps_per_period)
        return self._at(phase)

    def contact_force(self, phase: float, x: float) -> float:
        """``sum_j tilde k_j f_j(x)`` at one cycle phase (-)."""
        kd, gd, kb, eb = (a.ravel() for a in self._at(np.array([phase % 1.0])))
        b = self.backlash
        return float(
            np.sum(kd * np.maximum(x - gd - b, 0.0)) + np.sum(kb * np.minimum(x - eb + b, 0.0))
        )

    def rhs(self, tau: float, y: np.ndarray, frequency: float) -> np.ndarray:
        """Right-hand side ``(x', v')`` at continuous time (for ``scipy.integrate.solve_ivp``)."""
        phase = (frequency * tau / (2 * math.pi)) % 1.0
        f = self.contact_force(phase, float(y[0]))
        return np.array([y[1], self.force - 2 * self.zeta * y[1] - f])

    def quasi_static_dte(self, phase: np.ndarray) -> np.ndarray:
        """Drive-side static solution ``x`` of ``sum_j k_j max(x - b - g_j, 0) = F`` (-)."""
        kd, gd, _, _ = self._at(np.atleast_1d(np.asarray(phase, dtype=float)))
        out = np.empty(kd.shape[0])
        for i in range(kd.shape[0]):
            k, g = kd[i][kd[i] > 0], gd[i][kd[i] > 0]
            o = np.argsort(g)
            k, g = k[o], g[o]
            # on [g_m, g_{m+1}] the force is sum_{j<=m} k_j (y - g_j), y = x - b
            ck, ckg = np.cumsum(k), np.cumsum(k * g)
            y = (self.force + ckg) / ck
            nxt = np.append(g[1:], np.inf)
            m = int(np.argmax(y <= nxt))
            out[i] = y[m] + self.backlash
        return out

    def start_dte(self) -> float:
        """Quasi-static DTE at phase 0 (the sweep's starting point)."""
        return float(self.quasi_static_dte(np.array([0.0]))[0])

    def static_dte(self) -> float:
        """Mean quasi-static DTE over the cycle (-)."""
        return float(self.quasi_static_dte(np.arange(64) / 64).mean())


def itms_from_mesh_cycle(
    cycle: MeshCycle,
    *,
    zeta: float,
    backlash_m: float,
    length_scale_m: float | None = None,
    back_flank: BackFlank = "unmodified",
) -> ITMSModel:
    """The ITMS model of seed 003 Eq. 28 from a mesh cycle (per-pair compliance and gaps).

    Parameters
    ----------
    cycle : MeshCycle
        From :func:`~models.stiffness.mesh_cycle.mesh_cycle` (its compliance, profile error
        and separation per slot; its load ``F``).
    zeta : float
        Damping ratio (-).
    backlash_m : float
        Half backlash ``b`` on the line of action (m).
    length_scale_m : float, optional
        ``L`` (m); default ``b``.
    back_flank : {"unmodified", "mirror", "seed"}
        Back-flank profile (module notes, :func:`~models.dynamics.back_flank.back_flank_offset`).
    """
    L = backlash_m if length_scale_m is None else length_scale_m
    if not L > 0:
        raise ModelError("length scale must be > 0 (give length_scale_m when backlash is 0)")
    k0 = cycle.fvms_harmonics.mean
    if not k0 > 0:
        raise ModelError("the cycle's mean FVMS must be > 0")
    order = slice(None, None, -1)  # slot m = -1 first: increasing passage
    offsets = np.asarray(cycle.slot_offset)
    sigma = (cycle.phase[:, None] + offsets[None, :])[:, order].T.ravel()
    k = (1.0 / cycle.compliance_m_N)[:, order].T.ravel() / k0
    sep = cycle.separation_m[:, order].T.ravel()
    err = cycle.error_m[:, order].T.ravel()
    gap = err + sep
    touch = np.isfinite(gap)
    fill = float(gap[touch].max()) if touch.any() else 0.0
    on_path = sep == 0.0
    if not np.all(np.diff(sigma) > 0):
        raise ModelError("the cycle's slots do not stitch into one passage")
    return ITMSModel(
        zeta=float(zeta),
        force=cycle.load_N / (k0 * L),
        backlash=backlash_m / L,
        passage=sigma,
        drive_stiffness=np.where(touch, k, 0.0),
        drive_gap=np.where(touch, gap, fill) / L,
        back_stiffness=np.where(on_path, k, 0.0),
        back_error=back_flank_offset(err, back_flank) / L,
        slot_offsets=offsets.astype(float),
        length_scale_m=float(L),
        mean_stiffness_N_m=float(k0),
    )

r"""Single-DOF gear-pair models with backlash, non-dimensional (seed 003 Sec. 3, Eqs. 21-31).

Equation (all three models of the seed, one form):

.. math:: \ddot x + 2 \zeta \dot x + \tilde k(\tau)\, f(x - \tilde e(\tau)) = \tilde F

* ``x`` the dynamic transmission error (DTE) ``R_1 theta_1 - R_2 theta_2`` divided by a length
  ``L`` (default the half backlash ``b``, as in the seed's Eq. 27);
* ``tau = omega_n t`` with ``omega_n = sqrt(k_0 / m)``, ``k_0`` the mean mesh stiffness of the
  model and ``m = J_1 J_2 / (J_1 R_2^2 + J_2 R_1^2)`` the equivalent mass (Eq. 24a);
* ``zeta = c / (2 m omega_n)``; ``tilde F = f_0 / (k_0 L)`` with ``f_0 = T_1 / R_1`` (Eq. 24b);
* ``Lambda = 2 pi f_m / omega_n``: the mesh period is ``2 pi / Lambda`` in ``tau``;
* ``tilde k(tau) = k(t) / k_0 = 1 + sum_i tilde k_i cos(i Lambda tau + phi_i)`` and
  ``tilde e(tau) = e(t) / L``, both truncated Fourier series (Eq. 25) in the cycle phase
  ``Lambda tau / (2 pi)`` -- exactly :class:`~models.stiffness.mesh_cycle.Harmonics`;
* ``f`` the **dead-zone** backlash function with half-gap ``tilde b = b / L``::

      f(u) = u - b  (u > b),   0  (|u| <= b),   u + b  (u < -b).

  Seed Eq. 22/27 prints the contact force as ``h k (x - e)`` with ``h in {1, 0, -1}``; that
  jumps by ``k b`` at ``|u| = b`` and pulls the wrong way in back-side contact (SEED-NOTES
  16). The dead zone is continuous, has the potential ``V(u) = (|u| - b)^2 / 2`` outside the
  gap and 0 inside, and is the Kahraman-Singh form. Drive-side contact is ``u > b``, so the
  static equilibrium at the mean load is ``u = b + tilde F`` (constant stiffness). Damping is
  viscous on ``x`` at all times (Kahraman-Singh; the seed's ``h c`` form is dropped with h).

The three models of the seed (:func:`sdof_from_mesh_cycle`):

* ``"fvms"`` (Eq. 26): ``k = `` FVMS, ``e`` the gear error as a displacement excitation
  (by default the cycle's own profile errors, tip relief included, weighted by the pair
  stiffnesses, :func:`fvms_error_curve`; or given as harmonics in metres);
* ``"vvms"`` (Eq. 30): ``k = `` VVMS (secant ``F / x_s``, errors and corner contact inside),
  no separate error;
* ``"lste"`` (Eq. 31): constant stiffness ``k_0 = F / mean(x_s)`` and the alternating part of
  the LSTE as the excitation, so that the quasi-static solution is ``x - b = x_s(t)``
  exactly (Eq. 31 as printed has no mean load; with it the model keeps the static
  equilibrium);
* ``"itms"`` (Eq. 28): one stiffness and one error per tooth pair
  (:mod:`models.dynamics.itms`), partial contact loss and corner contact included.

Mean stiffness ``k_0`` (``reference_stiffness``): the seed scales each model by its own mean
stiffness. For VVMS and LSTE that is ``mean(F / x_s)`` resp. ``F / mean(x_s)`` with ``x_s`` the
loaded static transmission error, which *includes the profile errors* (seed Eq. 20b as
written): a rigid 5 um error on every pair cuts the VVMS ``k_0`` of the Kahraman pair at 340 N m
by 25 %, tip relief ``Delta = 1`` by 44 % (``omega_n`` by 25 %), though neither changes a tooth's
compliance; FVMS and ITMS keep the error-free mean FVMS. ``Lambda``, ``zeta`` and the Hz/rpm of
:mod:`models.dynamics.dimensional` inherit that choice; ``reference_stiffness="fvms"`` scales
every model by the mean FVMS instead (one frequency axis for all models and reliefs).

Back flanks (``back_flank``): the seed gives no back-side geometry. The cycle's profile errors
(tip relief) are on the drive flanks; by default the back flanks are unmodified involutes
(back contact at ``x < -b``); ``"mirror"`` relieves them alike, ``"seed"`` applies the drive-side
error to the back side as a displacement (seed Eqs. 26, 28 literally), which narrows the back
gap by the relief (:func:`~models.dynamics.back_flank.back_flank_offset`). A user-given error
series is a displacement excitation and shifts both flanks.

Stiffness and error come either from their Fourier series (``source="fourier"``, seed
Eq. 25, the cycle's ``*_harmonics``) or from the mesh-cycle curves themselves
(``source="curve"``: periodic linear interpolation of the cycle's arrays, every harmonic
kept; :class:`PeriodicCurve`).

References
----------
.. [1] W. Yu, C. K. Mechefske, Mech. Mach. Theory 96 (2016) 146-164, Sec. 3 (seed 003).
.. [2] A. Kahraman, R. Singh, "Non-linear dynamics of a spur gear pair", J. Sound Vib. 142
   (1990) 49-75 (dead-zone backlash).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike

from models.dynamics.back_flank import BACK_FLANKS, BackFlank
from models.dynamics.itms import itms_from_mesh_cycle
from models.errors import ModelError
from models.stiffness.mesh_cycle import Harmonics, MeshCycle

__all__ = [
    "MODELS",
    "DynamicModel",
    "PeriodicCurve",
    "SDOFModel",
    "dead_zone",
    "dead_zone_potential",
    "fvms_error_curve",
    "printed_contact_force",
    "sdof_from_mesh_cycle",
]

MODELS = ("fvms", "vvms", "lste", "itms")


class DynamicModel(Protocol):
    """What the integrators and sweeps need from a model (SDOF or ITMS).

    ``pair_tables(N)`` returns ``(kd, ed, kb, eb)``, each ``(2 N, P)``: drive-side stiffness and
    offset, back-side stiffness and offset of ``P`` tooth-pair columns at the ``2 N`` half
    steps of one mesh period (-); the contact force is
    ``sum_j kd_j max(x - ed_j - b, 0) + kb_j min(x - eb_j + b, 0)``.
    """

    @property
    def zeta(self) -> float:
        """Damping ratio (-)."""
        ...

    @property
    def force(self) -> float:
        """``tilde F`` (-)."""
        ...

    @property
    def backlash(self) -> float:
        """``tilde b`` (-)."""
        ...

    @property
    def length_scale_m(self) -> float:
        """``L`` (m)."""
        ...

    @property
    def mean_stiffness_N_m(self) -> float:  # noqa: N802 (unit in the name)
        """``k_0`` (N/m)."""
        ...

    @property
    def kind(self) -> str:
        """Model name."""
        ...

    def pair_tables(
        self, steps_per_period: int
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(kd, ed, kb, eb)`` at the ``2 N`` half steps, each ``(2 N, P)``."""
        ...

    def rhs(self, tau: float, y: np.ndarray, frequency: float) -> np.ndarray:
        """``(x', v')`` at continuous time ``tau`` (for ``scipy.integrate.solve_ivp``)."""
        ...

    def start_dte(self) -> float:
        """DTE to start a sweep from (units of ``L``), at rest."""
        ...


@dataclass(frozen=True)
class PeriodicCurve:
    """A curve over one mesh cycle, sampled at ``n`` uniform phases and interpolated linearly.

    The alternative to :class:`~models.stiffness.mesh_cycle.Harmonics` (same call signature)
    when every harmonic of a mesh-cycle curve is wanted (e.g. the FVMS steps at the
    single/double contact transitions).

    Attributes
    ----------
    values : numpy.ndarray
        Samples at phases ``i / n``, ``i = 0..n-1`` (unit of the curve).
    """

    values: np.ndarray

    def __post_init__(self) -> None:
        v = np.asarray(self.values, dtype=float)
        if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)):
            raise ModelError("`values` must be a 1-D finite array of >= 2 samples")

    @property
    def mean(self) -> float:
        """Mean over the cycle (trapezoid rule of the periodic interpolant = sample mean)."""
        return float(np.mean(self.values))

    def __call__(self, phase: ArrayLike) -> np.ndarray:
        """Evaluate at cycle phases ``tau`` (-), periodic with period 1."""
        v = np.asarray(self.values, dtype=float)
        n = v.size
        t = np.mod(np.asarray(phase, dtype=float), 1.0) * n
        return np.asarray(np.interp(t, np.arange(n + 1), np.append(v, v[0])))

    def scaled(self, scale: float, drop_mean: bool = False) -> PeriodicCurve:
        """``(values - [mean]) / scale``."""
        v = np.asarray(self.values, dtype=float)
        return PeriodicCurve((v - (v.mean() if drop_mean else 0.0)) / scale)


Series = Harmonics | PeriodicCurve


def dead_zone(u: ArrayLike, b: float) -> np.ndarray:
    """Dead-zone backlash function ``f(u)`` (continuous; ``b >= 0`` the half gap)."""
    u = np.asarray(u, dtype=float)
    return np.where(u > b, u - b, np.where(u < -b, u + b, 0.0))


def dead_zone_potential(u: ArrayLike, b: float) -> np.ndarray:
    """Potential ``V(u)`` with ``dV/du = f(u)``: ``(|u| - b)^2 / 2`` outside the gap, else 0."""
    u = np.asarray(u, dtype=float)
    return 0.5 * np.maximum(np.abs(u) - b, 0.0) ** 2


def printed_contact_force(u: ArrayLike, b: float) -> np.ndarray:
    """Seed Eq. 22 as printed, ``h u`` with ``h = (sgn(u - b) + sgn(u + b)) / 2`` (not used).

    Kept only to document SEED-NOTES 16: it jumps by ``b`` at ``|u| = b``.
    """
    u = np.asarray(u, dtype=float)
    return 0.5 * (np.sign(u - b) + np.sign(u + b)) * u


def _zero_series() -> Harmonics:
    return Harmonics(0.0, np.zeros(0), np.zeros(0))


@dataclass(frozen=True)
class SDOFModel:
    """Non-dimensional SDOF gear-pair model ``x'' + 2 zeta x' + k(tau) f(x - e(tau)) = F``.

    Attributes
    ----------
    zeta : float
        Damping ratio (-).
    force : float
        ``tilde F = f_0 / (k_0 L)`` (-).
    backlash : float
        Half gap ``tilde b = b / L`` (-), >= 0; 0 gives a linear spring.
    stiffness : Harmonics or PeriodicCurve
        ``tilde k = k / k_0`` over the mesh cycle phase (-); mean 1 when ``k_0`` is the
        model's own mean stiffness.
    error : Harmonics or PeriodicCurve
        ``tilde e`` over the mesh cycle phase (-).
    back_error : Harmonics or PeriodicCurve, optional
        Offset of the back-side contact (-): back contact where ``x - e_b < -b``. None (the
        default): ``error`` itself, the Kahraman-Singh displacement excitation ``f(x - e)``
        (a transmission error that shifts both flanks alike).
    length_scale_m : float
        ``L`` (m): dimensional DTE is ``L x``.
    mean_stiffness_N_m : float
        ``k_0`` (N/m); ``omega_n = sqrt(k_0 / m)``.
    kind : str
        ``"fvms"``, ``"vvms"``, ``"lste"`` or ``"custom"``.
    """

    zeta: float
    force: float
    backlash: float
    stiffness: Series = field(default_factory=lambda: Harmonics(1.0, np.zeros(0), np.zeros(0)))
    error: Series = field(default_factory=_zero_series)
    length_scale_m: float = 1.0
    mean_stiffness_N_m: float = math.nan
    kind: str = "custom"
    back_error: Series | None = None

    def __post_init__(self) -> None:
        if not (self.zeta >= 0 and self.backlash >= 0):
            raise ModelError("SDOFModel needs zeta >= 0 and backlash >= 0")

    def tables(self, frequency: float, steps_per_period: int) -> tuple[np.ndarray, np.ndarray]:
        """``tilde k`` and ``tilde e`` at the ``2 N`` half steps of one mesh period.

        Index ``j`` is ``tau = j h / 2`` with ``h = 2 pi / (Lambda N)``; periodic, so a
        fixed-step RK4 over whole periods needs nothing else. (Independent of ``Lambda``
        in phase: kept as an argument for clarity.)
        """
        del frequency  # the phase grid is the same for every Lambda
        phase = np.arange(2 * steps_per_period) / (2 * steps_per_period)
        return (
            np.ascontiguousarray(self.stiffness(phase), dtype=float),
            np.ascontiguousarray(self.error(phase), dtype=float),
        )

    def pair_tables(
        self, steps_per_period: int
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The :class:`DynamicModel` tables: one column, ``kd = kb = k``, ``ed = e``, ``eb = e_b``.

        ``e_b`` is ``back_error``, or ``error`` when that is None.
        """
        k, e = self.tables(1.0, steps_per_period)
        if self.back_error is None:
            eb = e
        else:
            phase = np.arange(2 * steps_per_period) / (2 * steps_per_period)
            eb = np.ascontiguousarray(self.back_error(phase), dtype=float)
        return k[:, None], e[:, None], k[:, None], eb[:, None]

    def start_dte(self) -> float:
        """Quasi-static DTE at phase 0 ignoring the stiffness variation: ``b + F + e_0``."""
        return self.static_dte() + self.error.mean

    def rhs(self, tau: float, y: np.ndarray, frequency: float) -> np.ndarray:
        """Right-hand side ``(x', v')`` at continuous time (for ``scipy.integrate.solve_ivp``)."""
        phase = frequency * tau / (2 * math.pi)
        k = float(self.stiffness(phase))
        e = float(self.error(phase))
        eb = e if self.back_error is None else float(self.back_error(phase))
        b = self.backlash
        u, w = y[0] - e, y[0] - eb
        f = (u - b if u > b else 0.0) + (w + b if w < -b else 0.0)
        return np.array([y[1], self.force - 2 * self.zeta * y[1] - k * f])

    def static_dte(self) -> float:
        """Static DTE at the mean load with the mean stiffness and no excitation: ``b + F``."""
        return self.backlash + self.force


def _scaled(h: Series, scale: float, drop_mean: bool = False) -> Series:
    if isinstance(h, PeriodicCurve):
        return h.scaled(scale, drop_mean)
    return Harmonics(
        0.0 if drop_mean else h.mean / scale,
        np.asarray(h.amplitude) / scale,
        np.asarray(h.phase_rad),
    )


def fvms_error_curve(cycle: MeshCycle) -> np.ndarray:
    r"""The FVMS model's gear error from the cycle's per-pair profile errors (m), per phase.

    .. math:: e_F(\tau) = \sum_{A \le s_i \le E} K_i e_i \Big/ \sum_{A \le s_i \le E} K_i

    the stiffness-weighted error of the pairs on the theoretical path: with it
    ``k_F (x - e_F) = sum_i K_i (x - e_i)``, the ITMS force (Eq. 28) while every pair on AE
    touches. It is the static transmission error of the classical model (no corner contact,
    no partial loss) less ``F / k_F``, so the quasi-static FVMS solution is that LSTE.
    """
    k = np.where(_in_path(cycle), 1.0 / cycle.compliance_m_N, 0.0)
    return np.asarray((k * cycle.error_m).sum(axis=1) / k.sum(axis=1))


def _in_path(cycle: MeshCycle) -> np.ndarray:
    """Pairs on the theoretical path AE: zero separation distance (checked against the FVMS)."""
    on = cycle.separation_m == 0.0
    k = 1.0 / cycle.compliance_m_N
    if not np.allclose(np.where(on, k, 0.0).sum(axis=1), cycle.fvms_N_m, rtol=1e-9):
        raise ModelError("cannot identify the pairs on the theoretical path of `cycle`")
    return np.asarray(on)


def _series(cycle: MeshCycle, name: str, source: str, n: int | None) -> Series:
    if source == "curve":
        return PeriodicCurve(
            np.asarray(
                getattr(cycle, {"fvms": "fvms_N_m", "vvms": "vvms_N_m", "lste": "lste_m"}[name]),
                dtype=float,
            )
        )
    h: Harmonics = getattr(cycle, f"{name}_harmonics")
    return h if n is None else Harmonics(h.mean, h.amplitude[:n], h.phase_rad[:n])


def _error_series(cycle: MeshCycle, source: str, n: int | None) -> Series:
    e = fvms_error_curve(cycle)
    if source == "curve":
        return PeriodicCurve(e)
    c = np.fft.rfft(e) / e.size
    nh = cycle.fvms_harmonics.amplitude.size if n is None else n
    k = slice(1, nh + 1)
    return Harmonics(float(c[0].real), 2 * np.abs(c[k]), np.angle(c[k]))


def _negated(h: Series) -> Series:
    if isinstance(h, PeriodicCurve):
        return PeriodicCurve(-np.asarray(h.values, dtype=float))
    # -A cos(phi) = A cos(phi + pi)
    return Harmonics(-h.mean, np.asarray(h.amplitude), np.asarray(h.phase_rad) + math.pi)


def sdof_from_mesh_cycle(
    cycle: MeshCycle,
    kind: str,
    *,
    zeta: float,
    backlash_m: float,
    error: Harmonics | PeriodicCurve | Literal["cycle"] | None = "cycle",
    length_scale_m: float | None = None,
    n_harmonics: int | None = None,
    source: Literal["fourier", "curve"] = "fourier",
    back_flank: BackFlank = "unmodified",
    reference_stiffness: Literal["model", "fvms"] | float = "model",
) -> SDOFModel:
    """The seed's FVMS, VVMS, LSTE or ITMS model from a mesh cycle.

    The cycle comes from :func:`~models.stiffness.mesh_cycle.mesh_cycle`.

    Parameters
    ----------
    cycle : MeshCycle
        Mesh cycle at the operating torque (its ``load_N`` is ``f_0``).
    kind : {"fvms", "vvms", "lste", "itms"}
        ``"itms"`` returns an :class:`~models.dynamics.itms.ITMSModel` (per-pair curves;
        ``error``, ``n_harmonics``, ``source`` and ``reference_stiffness`` do not apply).
    zeta : float
        Damping ratio (with respect to ``k_0``: ``c = 2 zeta sqrt(k_0 m)``).
    backlash_m : float
        Half backlash ``b`` on the line of action (m) (Table 3 gives ``2 b``).
    error : Harmonics, PeriodicCurve, "cycle" or None
        Gear error ``e(t)`` (m) of the FVMS model; ignored by the others. ``"cycle"`` (the
        default): the cycle's own profile errors (tip relief) as :func:`fvms_error_curve`,
        zero for an error-free cycle -- the FVMS model of seed Sec. 5.1 treats the relief as
        this displacement excitation. A series: a displacement excitation on both flanks
        (the back side follows it). None: no error, even when the cycle has relief.
    length_scale_m : float, optional
        ``L``; default ``b`` (then ``tilde b = 1``).
    n_harmonics : int, optional
        Truncate the Fourier series to this many harmonics (default: all of the cycle's).
    source : {"fourier", "curve"}
        Fourier series of the cycle (seed Eq. 25) or the sampled curves.
    back_flank : {"unmodified", "mirror", "seed"}
        What the back flanks carry of the cycle's drive-flank profile errors
        (:func:`~models.dynamics.back_flank.back_flank_offset`), for the FVMS model with
        ``error="cycle"`` and the ITMS model. Default ``"unmodified"``: the relief is on the
        drive flanks only.
    reference_stiffness : {"model", "fvms"} or float
        ``k_0`` of the scaling (``omega_n = sqrt(k_0 / m)``, ``tilde F``, ``zeta``).
        ``"model"`` (seed Eqs. 27, 30, 31): the model's own mean stiffness -- the mean FVMS,
        the mean VVMS ``mean(F / x_s)``, or ``F / mean(x_s)`` for the LSTE model. The last two
        are secant stiffnesses of the loaded static transmission error ``x_s``, which holds the
        profile errors: a rigid 5 um error on every pair of the Kahraman pair at 340 N m cuts
        the VVMS ``k_0`` by 25 %, tip relief ``Delta = 1`` by 44 % (``omega_n`` by 25 %), where
        the FVMS stays put. ``"fvms"``: the cycle's mean FVMS (error-free compliance of the
        pairs on the path, the same for every model, load and relief), so that ``Lambda`` is
        one frequency axis for all models; ``tilde k`` then has mean ``k_mean / k_F0``. A
        float: that ``k_0`` (N/m).
    """
    if kind not in MODELS:
        raise ModelError(f"unknown SDOF model {kind!r}; expected one of {MODELS}")
    if source not in ("fourier", "curve"):
        raise ModelError(f"`source` must be 'fourier' or 'curve', was {source!r}")
    if back_flank not in BACK_FLANKS:
        raise ModelError(f"`back_flank` must be one of {BACK_FLANKS}, was {back_flank!r}")
    if kind == "itms":
        return itms_from_mesh_cycle(  # type: ignore[return-value]
            cycle,
            zeta=zeta,
            backlash_m=backlash_m,
            length_scale_m=length_scale_m,
            back_flank=back_flank,
        )
    L = backlash_m if length_scale_m is None else length_scale_m
    if not L > 0:
        raise ModelError("length scale must be > 0 (give length_scale_m when backlash is 0)")
    F = cycle.load_N
    n = n_harmonics

    def cut(h: Series) -> Series:
        if n is None or isinstance(h, PeriodicCurve):
            return h
        return Harmonics(h.mean, h.amplitude[:n], h.phase_rad[:n])

    err: Series = _zero_series()
    back: Series | None = None
    if kind == "fvms":
        h = _series(cycle, "fvms", source, n)
        k_model = h.mean
        if isinstance(error, str):
            if error != "cycle":
                raise ModelError(
                    f"`error` must be Harmonics, PeriodicCurve, 'cycle' or None, was {error!r}"
                )
            err = _scaled(_error_series(cycle, source, n), L)
            if back_flank == "unmodified":
                back = _zero_series()
            elif back_flank == "mirror":
                back = _negated(err)
        elif error is not None:
            err = _scaled(cut(error), L)
    elif kind == "vvms":
        h = _series(cycle, "vvms", source, n)
        k_model = h.mean
    else:
        hx = _series(cycle, "lste", source, n)
        if not hx.mean > 0:
            raise ModelError("LSTE model needs a positive mean LSTE (torque > 0)")
        k_model = F / hx.mean
        h = Harmonics(k_model, np.zeros(0), np.zeros(0))
        err = _scaled(hx, L, drop_mean=True)
    k0 = _reference_stiffness(cycle, reference_stiffness, k_model)
    stiffness = _scaled(h, k0)
    return SDOFModel(
        zeta=zeta,
        force=F / (k0 * L),
        backlash=backlash_m / L,
        stiffness=stiffness,
        error=err,
        length_scale_m=L,
        mean_stiffness_N_m=k0,
        kind=kind,
        back_error=back,
    )


def _reference_stiffness(cycle: MeshCycle, reference: object, k_model: float) -> float:
    if isinstance(reference, str):
        if reference == "model":
            return float(k_model)
        if reference == "fvms":
            return float(cycle.fvms_harmonics.mean)
        raise ModelError(
            f"`reference_stiffness` must be 'model', 'fvms' or a stiffness, was {reference!r}"
        )
    k0 = float(reference)  # type: ignore[arg-type]
    if not (math.isfinite(k0) and k0 > 0):
        raise ModelError(f"`reference_stiffness` must be finite and > 0, was {reference!r}")
    return k0

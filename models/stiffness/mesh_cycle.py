r"""One mesh cycle of a spur pair: FVMS, VVMS and LSTE with corner contact (seed 003 Sec. 2).

Over one base pitch of pinion rotation (phase ``tau`` in [0, 1), ``tau = 0`` when a pair reaches
the start of contact A, the :meth:`~models.geometry.GearPair.pair_positions` convention), the
tooth pairs sit at ``s_m(tau) = A + (tau + m) p_b``. Every pair that could touch is a *slot*:
``m = -1`` (the approaching pair, before A) up to ``m = ceil(eps)`` (beyond E), so
``ceil(eps) + 2`` slots, slot 0 the most advanced (so corner contact can reach at most one
pair beyond each end: the effective contact ratio saturates near ``ceil(eps) + 1``, reached
only at torques far above a pair's rating, e.g. 3.0 for the Kahraman pair at 1e4 N m). At
each phase:

1. gaps ``g = e(s) + S(s)``: the profile error (tip relief, :mod:`models.stiffness.tip_relief`, or
   any callable) plus the separation distance outside AE
   (:func:`models.stiffness.corner_contact.separation_distance`; ``+inf`` with
   ``corner_contact=False``);
2. the compatibility conditions with the active set
   (:func:`models.stiffness.load_sharing.solve_load_sharing`): loads ``F_i``, LSTE ``x``.

Then:

* **FVMS** (Eqs. 18-19): ``K_F = sum_{A <= s_i <= E} 1 / C(s_i)``, the pairs in the theoretical
  path; independent of load and errors.
* **VVMS** (Eq. 20b): ``K_V = F / x``, the secant stiffness through the origin. That is the
  seed's definition, and the one its VVMS dynamic model needs: Eq. 29a writes the mesh force as
  ``k_V(t) x(t)``, whose static solution is the LSTE only if ``k_V = F / x_s``. It includes the
  errors and corner contact (through ``x``) and equals the FVMS at ``F = 0`` without errors
  (seed Sec. 2.6) as the limit ``F -> 0+``: ``x -> F / sum K`` over the pairs that touch. With
  errors at ``F = 0`` that limit is ``0`` wherever the smallest gap is open. Per pair (Eq. 20a)
  ``K_V^i = F_i / x = LSR_i K_V``. The secant needs ``x > 0``: errors are measured from the
  unmodified involute, material removed positive; a profile error that makes ``x <= 0`` is
  refused (shift it by a constant: loads do not change, ``x`` shifts by that constant).
* **Tangent stiffness** ``dF/dx = sum K_i`` over the loaded pairs, what a small vibration about
  the loaded state sees (not in the seed; returned alongside, equal to the VVMS when every
  loaded pair has zero gap).
* **Effective contact ratio**: the length of path over which one tooth pair carries load,
  in base pitches (seed Fig. 5), from the stitched load history of one pair with the start and
  end of load located by linear interpolation of ``x - g`` between phases.
* **Harmonics** of LSTE, FVMS and VVMS in the form of seed Eq. 25,
  ``f(tau) = f_0 + sum_k f_k cos(2 pi k tau + phi_k)``, from the DFT of the uniform phase grid.

The tooth-pair compliance ``C(s)`` (m/N, whole face width) is an input: any callable, e.g.
``lambda s: pair_compliance(pair, s).total`` from :mod:`models.stiffness.potential_energy`, or
an analytic one. It is evaluated once, at the distinct positions of the cycle clipped to
[A, E]: a pair in corner contact is loaded at the tip corner of the driving (recess) or driven
(approach) tooth, and its compliance is taken as that of a load at the tip, ``C(E)`` or
``C(A)``. (The mating flank is touched slightly lower than at E or A; ignoring that
overestimates the mating tooth's part of the compliance by a few per cent at most over the
corner-contact range, and only while the corner carries a small share.) The normal load is
``F = T / r_b1``. :func:`tabulate_compliance` makes a costly compliance cheap to call.

References
----------
.. [1] W. Yu, C. K. Mechefske, "Analytical modeling of spur gear corner contact effects",
   Mech. Mach. Theory 96 (2016) 146-164, Secs. 2.2-2.6, Eqs. 3-20, Figs. 4-6 (seed 003).
.. [2] S. H. Kasuba, J. W. Evans, "An extended model for determining dynamic loads in spur
   gearing", ASME J. Mech. Des. 103 (1981) 398-409 (FVMS and VVMS).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError
from models.geometry.gear_pair import GearPair
from models.stiffness.corner_contact import separation_distance
from models.stiffness.load_sharing import TOUCH_TOL_M, solve_load_sharing

__all__ = [
    "Harmonics",
    "MeshCycle",
    "MeshCycleGeometry",
    "TabulatedCompliance",
    "ToothPairHistory",
    "mesh_cycle",
    "prepare_mesh_cycle",
    "tabulate_compliance",
]

Compliance = Callable[[np.ndarray], np.ndarray]
ProfileError = Callable[[np.ndarray], np.ndarray]


# --- small result types -----------------------------------------------------------------------
@dataclass(frozen=True)
class Harmonics:
    r"""Fourier series over one mesh cycle, in the form of seed 003 Eq. 25.

    .. math:: f(\tau) = f_0 + \sum_{k=1}^{N} f_k \cos(2 \pi k \tau + \varphi_k)

    Attributes
    ----------
    mean : float
        ``f_0`` (unit of the curve).
    amplitude : numpy.ndarray
        ``f_k``, ``k = 1..N`` (unit of the curve), >= 0.
    phase_rad : numpy.ndarray
        ``phi_k`` (rad).
    """

    mean: float
    amplitude: np.ndarray
    phase_rad: np.ndarray

    def __call__(self, phase: ArrayLike) -> np.ndarray:
        """Evaluate the truncated series at cycle phases ``tau`` (-)."""
        tau = np.asarray(phase, dtype=float)[..., None]
        k = np.arange(1, self.amplitude.size + 1)
        terms = self.amplitude * np.cos(2 * np.pi * k * tau + self.phase_rad)
        return np.asarray(self.mean + terms.sum(axis=-1))


def _harmonics(values: np.ndarray, n_harmonics: int) -> Harmonics:
    c = np.fft.rfft(values) / values.size
    k = slice(1, n_harmonics + 1)
    return Harmonics(float(c[0].real), 2 * np.abs(c[k]), np.angle(c[k]))


@dataclass(frozen=True)
class ToothPairHistory:
    """The load of one tooth pair over its whole passage, stitched from the slots of a cycle.

    Attributes
    ----------
    position_m : numpy.ndarray
        Position on the line of action from T1 (m), increasing, step ``p_b / n_phases``.
    load_N : numpy.ndarray
        Load of the pair (N).
    load_sharing_ratio : numpy.ndarray
        ``F_i / F`` (-) (the ``F -> 0+`` limit at zero load).
    in_contact : numpy.ndarray
        Carries load (touches, at zero load), bool.
    """

    position_m: np.ndarray
    load_N: np.ndarray
    load_sharing_ratio: np.ndarray
    in_contact: np.ndarray


@dataclass(frozen=True)
class TabulatedCompliance:
    """A compliance tabulated on [A, E] and interpolated linearly; positions are clipped.

    Attributes
    ----------
    position_m : numpy.ndarray
        Grid on the path of contact (m from T1).
    compliance_m_N : numpy.ndarray
        ``C`` at the grid (m/N).
    """

    position_m: np.ndarray
    compliance_m_N: np.ndarray

    def __call__(self, s_m: ArrayLike) -> np.ndarray:
        """Compliance at positions ``s`` (m/N), same shape as ``s``."""
        s = np.asarray(s_m, dtype=float)
        return np.interp(s, self.position_m, self.compliance_m_N)


def tabulate_compliance(pair: GearPair, compliance: Compliance,
                        n_points: int = 401) -> TabulatedCompliance:
    """Tabulate ``compliance`` at ``n_points`` equally spaced positions on AE.

    Parameters
    ----------
    pair : GearPair
    compliance : callable
        ``C(s)`` (m/N), e.g. a potential-energy model that integrates per position.
    n_points : int
        Grid size, >= 2. Linear interpolation of a smooth compliance on 401 points over the
        path is accurate to ~1e-6 relative.

    Returns
    -------
    TabulatedCompliance
    """
    if int(n_points) != n_points or n_points < 2:
        raise ModelError(f"`n_points` must be an integer >= 2, was {n_points!r}")
    s = np.linspace(pair.start_of_contact, pair.end_of_contact, int(n_points))
    return TabulatedCompliance(s, _evaluate(compliance, s, "compliance", positive=True))


# --- the cycle --------------------------------------------------------------------------------
@dataclass(frozen=True)
class MeshCycle:
    """Loads, LSTE and mesh stiffnesses over one mesh cycle (seed 003 Figs. 4 and 6).

    Arrays over phases have shape ``(n_phases,)``; per-slot arrays ``(n_phases, n_slots)``.

    Attributes
    ----------
    phase : numpy.ndarray
        Cycle phase ``tau`` in [0, 1) (-), uniform; one cycle is one base pitch of pinion roll.
    slot_offset : numpy.ndarray
        ``m`` of each slot (int): slot ``k`` sits at ``A + (tau + m_k) p_b``; ``m_0`` the most
        advanced (outgoing), ``-1`` the approaching pair.
    positions_m : numpy.ndarray
        Nominal positions of the pairs on the line of action, from T1 (m).
    torque_Nm, load_N : float
        Pinion torque (N m) and normal load ``T / r_b1`` (N).
    compliance_m_N, error_m, separation_m : numpy.ndarray
        Per slot: compliance (m/N; at the clipped position), profile error (m), separation
        distance (m; 0 on AE, ``inf`` for pairs that cannot touch).
    loads_N, load_sharing_ratio, in_contact : numpy.ndarray
        Per slot: load (N), ``F_i / F`` (-), carries load (bool; at zero load: touches).
    corner_contact : numpy.ndarray
        Per slot: loaded outside the theoretical path AE (bool).
    lste_m : numpy.ndarray
        Loaded static transmission error ``x`` (m), corner contact included.
    fvms_N_m : numpy.ndarray
        Fixed-variable mesh stiffness, Eqs. 18-19 (N/m).
    vvms_N_m : numpy.ndarray
        Variable-variable mesh stiffness ``F / x``, Eq. 20b (N/m).
    tangent_stiffness_N_m : numpy.ndarray
        ``dF/dx``: sum of ``1/C`` over the loaded pairs (N/m).
    theoretical_contact_ratio, effective_contact_ratio : float
        ``AE / p_b`` and the loaded length of one pair over ``p_b`` (-).
    lste_harmonics, fvms_harmonics, vvms_harmonics : Harmonics
        Seed Eq. 25 coefficients (m, N/m, N/m).
    base_pitch_m : float
    """

    phase: np.ndarray
    slot_offset: np.ndarray
    positions_m: np.ndarray
    torque_Nm: float
    load_N: float
    compliance_m_N: np.ndarray
    error_m: np.ndarray
    separation_m: np.ndarray
    loads_N: np.ndarray
    load_sharing_ratio: np.ndarray
    in_contact: np.ndarray
    corner_contact: np.ndarray
    lste_m: np.ndarray
    fvms_N_m: np.ndarray
    vvms_N_m: np.ndarray
    tangent_stiffness_N_m: np.ndarray
    theoretical_contact_ratio: float
    effective_contact_ratio: float
    lste_harmonics: Harmonics
    fvms_harmonics: Harmonics
    vvms_harmonics: Harmonics
    base_pitch_m: float

    @property
    def has_corner_contact(self) -> bool:
        """Whether any pair carries load outside AE during the cycle."""
        return bool(self.corner_contact.any())

    def tooth_pair_history(self) -> ToothPairHistory:
        """Follow one tooth pair from one base pitch before A to beyond E (seed Figs. 4, 6)."""
        order = slice(None, None, -1)  # slot m = -1 first
        return ToothPairHistory(
            self.positions_m[:, order].T.ravel(),
            self.loads_N[:, order].T.ravel(),
            self.load_sharing_ratio[:, order].T.ravel(),
            self.in_contact[:, order].T.ravel(),
        )


@dataclass(frozen=True)
class MeshCycleGeometry:
    """The load-independent part of a mesh cycle (from :func:`prepare_mesh_cycle`).

    Solve it for a torque with :meth:`solve`; torque sweeps reuse the geometry.

    Attributes
    ----------
    phase, slot_offset, positions_m, compliance_m_N, error_m, separation_m : numpy.ndarray
        As in :class:`MeshCycle`.
    in_path : numpy.ndarray
        ``A <= s <= E`` per slot (bool).
    start_of_contact_m, end_of_contact_m, base_pitch_m, base_radius_1_m : float
    theoretical_contact_ratio : float
    """

    phase: np.ndarray
    slot_offset: np.ndarray
    positions_m: np.ndarray
    compliance_m_N: np.ndarray
    error_m: np.ndarray
    separation_m: np.ndarray
    in_path: np.ndarray
    start_of_contact_m: float
    end_of_contact_m: float
    base_pitch_m: float
    base_radius_1_m: float
    theoretical_contact_ratio: float

    def solve(self, torque_Nm: float, n_harmonics: int = 10) -> MeshCycle:
        """Loads, LSTE, FVMS and VVMS at pinion torque ``torque_Nm`` (N m), >= 0."""
        if not (math.isfinite(torque_Nm) and torque_Nm >= 0):
            raise ModelError(f"`torque_Nm` must be finite and >= 0 N m, was {torque_Nm!r}")
        n_phases = self.phase.size
        if int(n_harmonics) != n_harmonics or not (0 <= n_harmonics < n_phases // 2):
            raise ModelError(f"`n_harmonics` must be an integer in [0, n_phases // 2 = "
                             f"{n_phases // 2}), was {n_harmonics!r}")
        F = float(torque_Nm) / self.base_radius_1_m
        gap = self.error_m + self.separation_m
        ls = solve_load_sharing(self.compliance_m_N, gap, F)
        k = 1.0 / self.compliance_m_N
        x = ls.transmission_error_m
        fvms = np.where(self.in_path, k, 0.0).sum(axis=1)
        tangent = np.where(ls.in_contact, k, 0.0).sum(axis=1)
        if F > 0:
            if np.any(x <= 0):
                raise ModelError(
                    f"`error`: the loaded transmission error reaches {x.min():.3g} m <= 0, so "
                    "the VVMS F / x (seed 003 Eq. 20b) is undefined; measure profile errors "
                    "from the unmodified involute with material removed positive (adding a "
                    "constant to e leaves the loads unchanged)")
            vvms = F / x
        else:
            if np.any(x < -TOUCH_TOL_M):
                raise ModelError(f"`error` must not be negative where the pairs touch at zero "
                                 f"load (min {x.min():.3g} m): the VVMS F / x is undefined")
            vvms = np.where(x <= TOUCH_TOL_M, tangent, 0.0)
        corner = ls.in_contact & ~self.in_path & (ls.loads_N > 0)
        eff = self._effective_contact_ratio(x, gap, ls.in_contact, F)
        nh = int(n_harmonics)
        return MeshCycle(
            phase=self.phase, slot_offset=self.slot_offset, positions_m=self.positions_m,
            torque_Nm=float(torque_Nm), load_N=F, compliance_m_N=self.compliance_m_N,
            error_m=self.error_m, separation_m=self.separation_m, loads_N=ls.loads_N,
            load_sharing_ratio=ls.load_sharing_ratio, in_contact=ls.in_contact,
            corner_contact=corner, lste_m=x, fvms_N_m=fvms, vvms_N_m=vvms,
            tangent_stiffness_N_m=tangent,
            theoretical_contact_ratio=self.theoretical_contact_ratio,
            effective_contact_ratio=eff,
            lste_harmonics=_harmonics(x, nh), fvms_harmonics=_harmonics(fvms, nh),
            vvms_harmonics=_harmonics(vvms, nh), base_pitch_m=self.base_pitch_m,
        )

    def _effective_contact_ratio(self, x: np.ndarray, gap: np.ndarray, in_contact: np.ndarray,
                                 F: float) -> float:
        order = slice(None, None, -1)
        s = self.positions_m[:, order].T.ravel()
        if F == 0:
            # the limit F -> 0+: the part of AE where the pair's gap is the smallest
            path = self.in_path[:, order].T.ravel()
            touch = in_contact[:, order].T.ravel()
            return self.theoretical_contact_ratio * float(touch[path].mean())
        margin = (x[:, None] - gap)[:, order].T.ravel()  # > 0 where loaded; -inf: cannot touch
        m0, m1 = margin[:-1], margin[1:]
        s0, s1 = s[:-1], s[1:]
        h = s1 - s0
        p0, p1 = m0 > 0, m1 > 0
        length = np.where(p0 & p1, h, 0.0)
        A, E = self.start_of_contact_m, self.end_of_contact_m
        with np.errstate(invalid="ignore", divide="ignore"):
            # loaded at the left end only: up to the zero of the linear interpolant, or, next to
            # a pair that cannot touch (no corner contact modelled), up to the path end E
            frac0 = np.where(np.isfinite(m1), m0 / (m0 - m1) * h, np.clip(E, s0, s1) - s0)
            frac1 = np.where(np.isfinite(m0), m1 / (m1 - m0) * h, s1 - np.clip(A, s0, s1))
        length += np.where(p0 & ~p1, frac0, 0.0) + np.where(p1 & ~p0, frac1, 0.0)
        return float(length.sum() / self.base_pitch_m)


def _evaluate(fn: Callable[[np.ndarray], np.ndarray], s: np.ndarray, name: str,
              positive: bool) -> np.ndarray:
    """Call ``fn`` on the distinct values of ``s`` once; check shape and values."""
    uniq, inverse = np.unique(s, return_inverse=True)
    try:
        raw = np.asarray(fn(uniq), dtype=float)
        out = np.broadcast_to(raw, uniq.shape)
    except ValueError as exc:
        raise ModelError(f"`{name}` must return an array of its input's shape {uniq.shape}, "
                         f"returned shape {np.shape(raw)}") from exc
    ok = np.isfinite(out) & (out > 0) if positive else np.isfinite(out)
    if not np.all(ok):
        bad = out[~ok].ravel()[0]
        what = "finite and > 0" if positive else "finite"
        raise ModelError(f"`{name}` must return {what} values, returned {bad!r} at "
                         f"s = {uniq[~ok][0]!r} m")
    return np.asarray(out[inverse.reshape(s.shape)], dtype=float)


def prepare_mesh_cycle(
    pair: GearPair,
    compliance: Compliance,
    *,
    error: ProfileError | None = None,
    n_phases: int = 200,
    corner_contact: bool = True,
) -> MeshCycleGeometry:
    """The load-independent part of :func:`mesh_cycle`: positions, compliances, gaps.

    Parameters
    ----------
    pair : GearPair
    compliance : callable
        Tooth-pair compliance ``C(s)`` (m/N) at positions ``s`` on AE (m from T1), array in,
        same shape out (a scalar is broadcast).
    error : callable, optional
        Profile error ``e(s)`` of a tooth pair (m), e.g. a
        :class:`~models.stiffness.tip_relief.TipRelief`; evaluated at positions clipped to AE.
        None: error-free involutes.
    n_phases : int
        Phases per cycle, >= 16 (100 or more for smooth curves).
    corner_contact : bool
        Model contact outside AE (seed 003 Sec. 2.3). False: pairs outside AE never touch, the
        classical model whose LSTE jumps at the single/double-contact transitions.

    Returns
    -------
    MeshCycleGeometry
    """
    if int(n_phases) != n_phases or n_phases < 16:
        raise ModelError(f"`n_phases` must be an integer >= 16, was {n_phases!r}")
    n_phases = int(n_phases)
    eps = pair.contact_ratio
    A, E, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    n_slots = math.ceil(eps) + 2
    phase = np.arange(n_phases) / n_phases
    positions = pair.pair_positions(phase, n_slots) - pb  # m = n_slots - 2 ... -1
    offsets = np.arange(n_slots - 2, -2, -1)
    in_path = (positions >= A) & (positions <= E)
    clipped = np.clip(positions, A, E)
    c = _evaluate(compliance, clipped, "compliance", positive=True)
    e = (np.zeros(positions.shape) if error is None
         else _evaluate(error, clipped, "error", positive=False))
    if corner_contact:
        sep = separation_distance(pair, positions)
    else:
        sep = np.where(in_path, 0.0, np.inf)
    return MeshCycleGeometry(phase, offsets, positions, c, e, sep, in_path, A, E, pb,
                             pair.base_radius(1), eps)


def mesh_cycle(
    pair: GearPair,
    compliance: Compliance,
    torque_Nm: float,
    *,
    error: ProfileError | None = None,
    n_phases: int = 200,
    n_harmonics: int = 10,
    corner_contact: bool = True,
) -> MeshCycle:
    r"""FVMS, VVMS, loads and LSTE over one mesh cycle (seed 003 Eqs. 5-20).

    Parameters
    ----------
    pair : GearPair
    compliance : callable
        Tooth-pair compliance ``C(s)`` (m/N, whole face width) at positions ``s`` (m from T1).
    torque_Nm : float
        Pinion torque ``T`` (N m), >= 0; normal load ``F = T / r_b1``.
    error : callable, optional
        Profile error of a tooth pair ``e(s)`` (m), e.g. from
        :func:`~models.stiffness.tip_relief.tip_relief`.
    n_phases : int
        Phases per cycle (>= 16).
    n_harmonics : int
        Harmonics kept in the Fourier coefficients (< n_phases / 2).
    corner_contact : bool
        Include contact outside the theoretical path (seed 003 Sec. 2.3).

    Returns
    -------
    MeshCycle

    Notes
    -----
    At each phase, with gaps ``g_i = e(s_i) + S(s_i)`` and ``K_i = 1 / C_i``:

    .. math::

        x = C_i F_i + g_i \;(F_i > 0), \quad \sum_i F_i = F, \qquad
        K_F = \sum_{A \le s_i \le E} K_i, \qquad K_V = F / x .

    Examples
    --------
    A constant compliance without errors and without load: two pairs over 75 % of the cycle of
    the Kahraman pair (``eps = 1.7547``: 151 of 200 phases), one for the rest; the VVMS is the
    FVMS (seed 003 Sec. 2.6).

    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("kahraman-blankenship").pair
    >>> r = mesh_cycle(g, lambda s: np.full(np.shape(s), 1e-8), 0.0, n_phases=200)
    >>> int((r.fvms_N_m > 1.5e8).sum()), bool(np.allclose(r.vvms_N_m, r.fvms_N_m))
    (151, True)
    >>> round(r.effective_contact_ratio, 4), r.has_corner_contact
    (1.7547, False)
    """
    geo = prepare_mesh_cycle(pair, compliance, error=error, n_phases=n_phases,
                             corner_contact=corner_contact)
    return geo.solve(torque_Nm, n_harmonics)

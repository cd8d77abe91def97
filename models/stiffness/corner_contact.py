r"""Corner contact: separation distances outside the path of contact, and seed 003's case logic.

Under load the teeth of the loaded pair deflect, the transmission error ``x`` grows, and a pair
just outside the theoretical path of contact AE can touch: the tip corner of the *wheel* meets
the pinion flank before A (approach, premature engagement) and the tip corner of the *pinion*
stays on the wheel flank after E (recess, delayed release). Whether it does is decided by the
separation distance ``S`` of that pair: the transmission error at which its rigid profiles
touch (seed 003 Sec. 2.3.1; Lin et al. [2]). In the compatibility conditions the pair then
enters with a gap ``g = S + e`` (:mod:`models.stiffness.load_sharing`).

Geometry and conventions
------------------------
Positions ``s`` lie on the line of action, measured from T1 (:class:`~models.geometry.GearPair`);
a pair's *nominal* position is where its (extended) involutes would cross the line of action at
the current pinion angle, so pairs sit one base pitch apart and a pair outside AE has
``s < A`` or ``s > E``. The position is tied to the **pinion** angle and the load shows up as a
lag of the wheel, as in the transmission error ``x = r_b1 theta_1 - r_b2 theta_2`` of seed 003
(Eq. 3). ``S(s)`` is therefore the lag of the wheel (m on the line of action) at which the
corner touches, with the pinion held at its nominal angle.

Every involute of a base circle ``r_b`` carries a constant *involute coordinate*
``psi(P) = phi(P) + inv(arccos(r_b / |P|))`` (polar angle of the point plus the involute
function of its pressure angle), and ``r_b (psi(P) - psi_flank)`` is the distance from ``P`` to
that flank along their common normal, the base tangent through ``P``: rotating the flank's gear
by ``psi(P) - psi_flank`` brings the flank through ``P``. With O1 at the origin, T1 at
``(r_b1, 0)``, the line of action ``(r_b1, s)`` and O2 at ``(r_b1 + r_b2, L)``,
``L = a' sin(alpha')``, the pinion turning counter-clockwise:

*Recess* (``s > E``): the pinion tip corner is the point of its involute at the tip radius,
which sat at E a rotation ``(s - E) / r_b1`` ago,

.. math::

    P = r_{a1} \left(\cos(\alpha_{E} + \tfrac{s - E}{r_{b1}}),\
                     \sin(\alpha_{E} + \tfrac{s - E}{r_{b1}})\right), \quad
    \tan \alpha_E = E / r_{b1},

and, with ``d = O2 - P`` (pointing back to O2), ``r_2 = |d|``,
``phi'_2 = atan2(d_y, d_x)``,

.. math::

    S_r(s) = r_{b2} \left(\varphi'_2 + \operatorname{inv} \arccos \frac{r_{b2}}{r_2}\right)
             - (L - s),

exact and in closed form because the corner (on the pinion) is held still while the wheel lags.

*Approach* (``s < A``): the wheel tip corner ``P'`` is the point of the wheel involute at the
wheel tip radius, which reaches A after a further wheel rotation ``(A - s) / r_b2``. Held with
the wheel, advancing the pinion (wheel fixed) gives the closed form

.. math::

    G(s) = r_{b1} \left(\varphi_1(P') + \operatorname{inv} \arccos \frac{r_{b1}}{|P'|}\right) - s,

but here the corner moves with the lagging wheel. A lag ``x`` at pinion position ``s`` is the
same relative configuration as an advance ``x`` at position ``s - x`` (shift both gears along
the conjugate motion by ``x``), so the lag-convention separation solves

.. math:: S_a = G(s - S_a),

solved by Newton's method (``G'`` by central differences) to 1e-16 m or 1e-13 relative in three
steps (``|G'| ~ 2 S / |s - A|`` is small, so ``S = G(s)`` is already a close start).
Holding the wheel and advancing the pinion instead would move the position by ``S`` (under
20 um for the Kahraman pair), a second-order change.

``S = 0`` on AE, ``S`` grows quadratically away from A and E (zero slope at both: the corner
leaves along the flank's normal), and ``S = +inf`` where the corner cannot reach the mating
involute (the corner's radius about the mating centre below the mating base radius, or the
nominal position beyond T1 or T2, where the mating flank has not reached the line of action:
FZG-C has A < p_b) or lies more than one base pitch outside the path (such a pair would also
have to pass the next tooth; its separation is far beyond any elastic deflection).

The case logic of seed 003 (Eqs. 9-17, Table 1)
-----------------------------------------------
In the single-contact zone, pair #2 carries the load; pair #1 (outgoing, ``s_2 + p_b > E``)
and pair #3 (incoming, ``s_2 - p_b < A``) may be in corner contact. With ``e^{pq} = e_p - e_q``
and ``D = C_1 C_2 + C_2 C_3 + C_1 C_3`` the cases, written out from the compatibility
conditions (the print is garbled, SEED-NOTES 14):

* both in corner contact (Eq. 16a-d)

  .. math::

      x &= [C_2 (C_1 C_3 F + C_3 S_{r1} + C_1 S_{a3}) + C_1 C_2 e_3 + C_2 C_3 e_1
            + C_1 C_3 e_2] / D \\
      F_1 &= [C_2 C_3 F - C_3 e^{12} - C_2 e^{13} - (C_2 + C_3) S_{r1} + C_2 S_{a3}] / D \\
      F_2 &= [C_1 C_3 F - C_3 e^{21} - C_1 e^{23} + C_3 S_{r1} + C_1 S_{a3}] / D \\
      F_3 &= [C_1 C_2 F - C_2 e^{31} - C_1 e^{32} + C_2 S_{r1} - (C_1 + C_2) S_{a3}] / D

* pair #3 only (Eq. 10a-c): ``x = [C_2 (C_3 F + S_{a3}) + C_2 e_3 + C_3 e_2] / (C_2 + C_3)``,
  ``F_2 = (C_3 F + S_{a3} + e^{32}) / (C_2 + C_3)``,
  ``F_3 = (C_2 F - S_{a3} - e^{32}) / (C_2 + C_3)``;
* pair #1 only (Eq. 13a-c): ``x = [C_2 (C_1 F + S_{r1}) + C_1 e_2 + C_2 e_1] / (C_1 + C_2)``,
  ``F_1 = (C_2 F - S_{r1} - e^{12}) / (C_1 + C_2)``,
  ``F_2 = (C_1 F + S_{r1} + e^{12}) / (C_1 + C_2)``;
* neither (Eqs. 11, 14, 17): ``x = C_2 F + e_2``, ``F_2 = F``;

starting from both and falling back when a load comes out non-positive (F1 <= 0: case ①, then
F3 <= 0: Eq. 11; F3 <= 0: case ②, then F1 <= 0: Eq. 14; both: Eq. 17). Pair #2 is never dropped
(seed 003's second assumption). :func:`ncr_corner_contact` implements exactly this;
:func:`models.stiffness.load_sharing.solve_load_sharing` is the general form (any number of
pairs, Table 2) that :mod:`models.stiffness.mesh_cycle` uses, and the tests check that the two
agree.

References
----------
.. [1] W. Yu, C. K. Mechefske, "Analytical modeling of spur gear corner contact effects",
   Mech. Mach. Theory 96 (2016) 146-164, Sec. 2.3, Eqs. 9-17, Table 1 (seed 003).
.. [2] H. H. Lin, J. Wang, F. B. Oswald, J. J. Coy, "Effect of extended tooth contact on the
   modeling of spur gear transmissions", Gear Technology 11(4) (1994) 18-25.
.. [3] R. G. Munro, D. Palmer, L. Morrish, "An experimental method to measure gear tooth
   stiffness throughout and beyond the path of contact", Proc. IMechE C 215 (2001) 793-803.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError
from models.geometry.gear_pair import GearPair
from models.geometry.involute import inv
from models.stiffness.load_sharing import LoadSharing

__all__ = ["ncr_corner_contact", "separation_distance"]

_FIXED_POINT_TOL_M = 1e-16
_FIXED_POINT_RTOL = 1e-13
_FIXED_POINT_MAX_ITER = 30


def _frame(pair: GearPair) -> tuple[float, float, float, float, float, float, float]:
    rb1, rb2 = pair.base_radius(1), pair.base_radius(2)
    return (rb1, rb2, pair.line_of_action_length, pair.start_of_contact, pair.end_of_contact,
            pair.tip_radius(1), pair.tip_radius(2))


def _recess(pair: GearPair, s: np.ndarray) -> np.ndarray:
    """Closed-form S_r for nominal positions ``s >= E`` (lag convention); inf if unreachable."""
    rb1, rb2, L, _, E, ra1, _ = _frame(pair)
    ang = np.arctan2(E, rb1) + (s - E) / rb1
    px, py = ra1 * np.cos(ang), ra1 * np.sin(ang)
    dx, dy = (rb1 + rb2) - px, L - py  # from the corner back to O2
    r2 = np.hypot(dx, dy)
    ok = r2 >= rb2
    alpha = np.arccos(np.where(ok, rb2 / r2, 1.0))
    phi = np.arctan2(dy, dx)
    out = rb2 * (phi + inv(alpha)) - (L - s)
    return np.where(ok, out, np.inf)


def _approach_advance(frame: tuple[float, ...], s: np.ndarray) -> np.ndarray:
    """Closed-form advance gap G(s) for ``s <= A`` (wheel held, pinion advanced)."""
    rb1, rb2, L, A, _, _, ra2 = frame
    # the wheel tip corner: the LOA point A seen from O2, turned back (counter-clockwise)
    ang = np.arctan2(A - L, -rb2) + (A - s) / rb2
    px, py = rb1 + rb2 + ra2 * np.cos(ang), L + ra2 * np.sin(ang)
    r1 = np.hypot(px, py)
    ok = r1 >= rb1
    alpha = np.arccos(np.where(ok, rb1 / r1, 1.0))
    out = rb1 * (np.arctan2(py, px) + inv(alpha)) - s
    return np.where(ok, out, np.inf)


def _approach(pair: GearPair, s: np.ndarray) -> np.ndarray:
    """S_a in the lag convention: the root of ``R(S) = S - G(s - S)`` by Newton's method."""
    frame = _frame(pair)
    gap = _approach_advance(frame, s)  # the start: S = G(s), off by ~G' S
    fin = np.isfinite(gap)
    h = 1e-7
    for _ in range(_FIXED_POINT_MAX_ITER):
        sp = s - np.where(fin, gap, 0.0)
        g = _approach_advance(frame, sp)
        with np.errstate(invalid="ignore"):  # inf - inf where the corner cannot reach
            slope = (_approach_advance(frame, sp + h) - _approach_advance(frame, sp - h)) / (2 * h)
        ok = fin & np.isfinite(g) & np.isfinite(slope)
        step = np.where(ok, (gap - g) / np.where(ok, 1.0 + slope, 1.0), 0.0)
        fin = ok
        gap = np.where(fin, gap - step, np.inf)
        if not np.any(np.abs(step) > _FIXED_POINT_TOL_M
                      + _FIXED_POINT_RTOL * np.where(fin, gap, 0.0)):
            break
    return gap


def separation_distance(pair: GearPair, s_m: ArrayLike) -> np.ndarray:
    r"""Separation distance of a tooth pair at nominal position ``s`` (m on the line of action).

    Parameters
    ----------
    pair : GearPair
    s_m : array_like
        Nominal positions of the pair on the line of action, from T1 (m), any shape.

    Returns
    -------
    numpy.ndarray
        ``S`` (m), same shape: 0 on the path of contact ``A <= s <= E``; the approach separation
        ``S_a`` (wheel tip corner against the pinion flank) for ``s < A``; the recess separation
        ``S_r`` (pinion tip corner against the wheel flank) for ``s > E``; ``+inf`` more than one
        base pitch outside the path, beyond T1 or T2 (no mating involute on the line of action
        there), or where the corner cannot reach the mating involute.

    Notes
    -----
    Exact rigid-body geometry (Lin et al. 1994, seed 003 ref. [24]); formulas in the module
    docstring. The lag convention: the pinion sits at its nominal angle, the wheel lags by
    ``S / r_b2`` when the corner touches. Near the path ends
    ``S ~ k (s - E)^2`` (Munro's approximation), with zero slope at A and E.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("kahraman-blankenship").pair
    >>> s = separation_distance(g, [g.start_of_contact, g.end_of_contact, g.end_of_contact + 1e-3])
    >>> [round(float(v) * 1e6, 2) for v in s]
    [0.0, 0.0, 10.01]
    """
    s = np.asarray(s_m, dtype=float)
    if not np.all(np.isfinite(s)):
        raise ModelError("`s_m` must be finite positions (m)")
    A, E, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    L = pair.line_of_action_length
    out = np.full(s.shape, np.inf)
    out[(s >= A) & (s <= E)] = 0.0
    # the mating flank must exist on the line of action: s > 0 (pinion), s < L (wheel)
    before = (s < A) & (s >= A - pb) & (s > 0)
    after = (s > E) & (s <= E + pb) & (s < L)
    if np.any(before):
        out[before] = _approach(pair, s[before])
    if np.any(after):
        out[after] = _recess(pair, s[after])
    # outside the path the rigid profiles never overlap; clear rounding below zero at A and E
    # and refuse anything else (a diverged iteration) as "cannot touch"
    bad = ~(out >= -1e-15)
    out[bad] = np.inf
    return np.maximum(out, 0.0)


def ncr_corner_contact(
    compliance: ArrayLike,
    error: ArrayLike,
    recess_separation_m: ArrayLike,
    approach_separation_m: ArrayLike,
    load_N: ArrayLike,
) -> LoadSharing:
    r"""Seed 003's explicit case logic for three pairs in the single-contact zone (Eqs. 9-17).

    Parameters
    ----------
    compliance : array_like
        ``(C_1, C_2, C_3)`` (m/N), shape ``(..., 3)``: outgoing pair #1 (recess side), loaded
        middle pair #2, incoming pair #3 (approach side).
    error : array_like
        Profile errors ``(e_1, e_2, e_3)`` (m), broadcastable to ``compliance``.
    recess_separation_m : array_like
        ``S_r1`` of pair #1 (m), shape ``(...)``; ``+inf`` if it cannot touch.
    approach_separation_m : array_like
        ``S_a3`` of pair #3 (m), shape ``(...)``; ``+inf`` if it cannot touch.
    load_N : array_like
        Total normal load ``F`` (N), > 0.

    Returns
    -------
    LoadSharing
        Loads ``(F_1, F_2, F_3)`` and the LSTE ``x`` of Table 1.

    Notes
    -----
    The case formulas are in the module docstring. This is the seed's procedure for
    ``1 < eps < 2`` and is kept as the literal reading of Table 1; the mesh cycle uses the
    general active set, which agrees wherever pair #2 stays loaded.
    """
    c = np.asarray(compliance, dtype=float)
    if c.shape[-1:] != (3,) or not np.all(np.isfinite(c) & (c > 0)):
        raise ModelError(f"`compliance` must have shape (..., 3) with finite values > 0 m/N, "
                         f"was shape {c.shape}")
    e = np.broadcast_to(np.asarray(error, dtype=float), c.shape)
    f = np.asarray(load_N, dtype=float)
    if not np.all(np.isfinite(f) & (f > 0)):
        raise ModelError("`load_N` must be finite and > 0 N")
    sr = np.asarray(recess_separation_m, dtype=float)
    sa = np.asarray(approach_separation_m, dtype=float)
    shape = np.broadcast_shapes(c.shape[:-1], f.shape, sr.shape, sa.shape)
    c1, c2, c3 = (np.broadcast_to(c[..., i], shape) for i in range(3))
    e1, e2, e3 = (np.broadcast_to(e[..., i], shape) for i in range(3))
    f = np.broadcast_to(f, shape)
    can1, can3 = np.broadcast_to(np.isfinite(sr), shape), np.broadcast_to(np.isfinite(sa), shape)
    s1 = np.where(can1, sr, 0.0)
    s3 = np.where(can3, sa, 0.0)
    e12, e13, e21, e23, e31, e32 = e1 - e2, e1 - e3, e2 - e1, e2 - e3, e3 - e1, e3 - e2

    # case 3: both in corner contact (Eq. 16a-d)
    d = c1 * c2 + c2 * c3 + c1 * c3
    x16 = (c2 * (c1 * c3 * f + c3 * s1 + c1 * s3) + c1 * c2 * e3 + c2 * c3 * e1
           + c1 * c3 * e2) / d
    f1_16 = (c2 * c3 * f - c3 * e12 - c2 * e13 - (c2 + c3) * s1 + c2 * s3) / d
    f2_16 = (c1 * c3 * f - c3 * e21 - c1 * e23 + c3 * s1 + c1 * s3) / d
    f3_16 = (c1 * c2 * f - c2 * e31 - c1 * e32 + c2 * s1 - (c1 + c2) * s3) / d
    # case 1: pair #3 only (Eq. 10a-c)
    x10 = (c2 * (c3 * f + s3) + c2 * e3 + c3 * e2) / (c2 + c3)
    f2_10 = (c3 * f + s3 + e32) / (c2 + c3)
    f3_10 = (c2 * f - s3 - e32) / (c2 + c3)
    # case 2: pair #1 only (Eq. 13a-c)
    x13 = (c2 * (c1 * f + s1) + c1 * e2 + c2 * e1) / (c1 + c2)
    f1_13 = (c2 * f - s1 - e12) / (c1 + c2)
    f2_13 = (c1 * f + s1 + e12) / (c1 + c2)
    # neither (Eqs. 11, 14, 17)
    x17 = c2 * f + e2

    both = can1 & can3 & (f1_16 > 0) & (f3_16 > 0)
    # case 3 with F1 <= 0 only, or pair #1 unable to touch: case 1, then Eq. 11 if F3 <= 0
    go1 = (can1 & can3 & (f1_16 <= 0) & (f3_16 > 0)) | (~can1 & can3)
    only3 = go1 & (f3_10 > 0)
    # case 3 with F3 <= 0 only, or pair #3 unable to touch: case 2, then Eq. 14 if F1 <= 0
    go2 = (can1 & can3 & (f3_16 <= 0) & (f1_16 > 0)) | (can1 & ~can3)
    only1 = go2 & (f1_13 > 0)
    # otherwise (both non-positive in case 3, or a fallback failing): Eq. 17

    x = np.select([both, only3, only1], [x16, x10, x13], x17)
    f1 = np.select([both, only1], [f1_16, f1_13], 0.0)
    f2 = np.select([both, only3, only1], [f2_16, f2_10, f2_13], f)
    f3 = np.select([both, only3], [f3_16, f3_10], 0.0)
    loads = np.stack([f1, f2, f3], axis=-1)
    in_contact = np.stack([both | only1, np.ones(shape, bool), both | only3], axis=-1)
    return LoadSharing(x, loads, loads / f[..., None], in_contact, np.array(f))

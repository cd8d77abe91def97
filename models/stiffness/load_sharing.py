r"""Static load sharing among the tooth pairs of a spur mesh: seed 003, Eqs. 5-8 and 17.

At one mesh position the pairs ``i = 1..n`` that can touch each have a compliance ``C_i``
(m/N, whole face width) and a *gap* ``g_i`` (m): the profile error ``e_i`` (manufacturing error
plus profile modification, positive where material is missing), plus, for a pair outside the
theoretical path of contact, its separation distance ``S_i``
(:mod:`models.stiffness.corner_contact`).
The compatibility conditions of seed 003 (Eqs. 5a-c, 9, 12, 15) say that every loaded pair
shows the same transmission error ``x`` and that the loads add up to the total normal load:

.. math::

    x = C_i F_i + g_i \quad (F_i > 0), \qquad \sum_i F_i = F,

and a pair that would need a non-positive load leaves contact (``F_i = 0``, its gap stays open:
``g_i \ge x``). Eliminating the loads gives the closed forms the extraction garbled
(SEED-NOTES 14), here written out. For two pairs (Eq. 6a-c), with ``e^{pq} = e^p - e^q``:

.. math::

    x = \frac{C_1 C_2 F + C_1 e_2 + C_2 e_1}{C_1 + C_2}, \quad
    F_1 = \frac{C_2 F + e^{21}}{C_1 + C_2}, \quad F_2 = \frac{C_1 F - e^{21}}{C_1 + C_2},

so that ``LSR_1 = (C_2 + e^{21}/F) / (C_1 + C_2)`` (Eq. 7). For ``n`` pairs (Eq. 8a-c):

.. math::

    x = \frac{\left(\prod_p C_p\right) F + \sum_p \left(\prod_{q \ne p} C_q\right) e_p}
             {\sum_p \prod_{q \ne p} C_q}, \qquad
    F_i = \frac{\left(\prod_{q \ne i} C_q\right) F
                - \sum_p \left(\prod_{q \ne i, p} C_q\right) e^{ip}}
               {\sum_p \prod_{q \ne p} C_q},

which is the stiffness-weighted form ``x = (F + \sum_p K_p e_p) / \sum_p K_p`` with
``K_p = 1 / C_p`` multiplied through by ``\prod_p C_p``. The corner-contact cases of Eqs. 9-16
are the same formulas with ``e`` replaced by the gap ``g = e + S``.

The active set (which pairs carry load) is found as seed 003 does (Eqs. 11, 14, 17): solve with
every pair that can touch, drop the pairs with ``F_i <= 0`` and solve again. Dropping a pair
with ``F_i <= 0`` lowers ``x`` (its term ``(x - g_i) K_i`` was non-positive), so the dropped
pairs stay open and the iteration ends, after at most ``n - 1`` rounds, at the unique solution
of the complementarity problem ``sum_i K_i max(0, x - g_i) = F`` (the left side is increasing in
``x``).

References
----------
.. [1] W. Yu, C. K. Mechefske, "Analytical modeling of spur gear corner contact effects",
   Mech. Mach. Theory 96 (2016) 146-164, Eqs. 5-17 (seed 003).
.. [2] H. H. Lin, J. Wang, F. B. Oswald, J. J. Coy, "Effect of extended tooth contact on the
   modeling of spur gear transmissions", Gear Technology 11(4) (1994) 18-25.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError

__all__ = [
    "LoadSharing",
    "load_sharing_closed_form",
    "load_sharing_two_pairs",
    "solve_load_sharing",
]

#: Gaps within this distance (m) of the smallest count as touching at zero load.
TOUCH_TOL_M = 1e-13


@dataclass(frozen=True)
class LoadSharing:
    """Solution of the compatibility conditions at one or many mesh positions.

    Attributes
    ----------
    transmission_error_m : numpy.ndarray
        Loaded static transmission error ``x`` (m), shape ``(...)``.
    loads_N : numpy.ndarray
        Load ``F_i`` of each pair (N), shape ``(..., n)``; zero for pairs out of contact
        (negative values only from the closed forms, which do not drop pairs).
    load_sharing_ratio : numpy.ndarray
        ``F_i / F`` (-), shape ``(..., n)``. At ``F = 0`` the limit ``F -> 0+``:
        ``K_i / sum K`` over the touching pairs (NaN from the closed forms).
    in_contact : numpy.ndarray
        Pairs carrying load (at ``F = 0``: pairs touching), bool, shape ``(..., n)``.
    load_N : numpy.ndarray
        Total normal load ``F`` (N), shape ``(...)``.
    """

    transmission_error_m: np.ndarray
    loads_N: np.ndarray
    load_sharing_ratio: np.ndarray
    in_contact: np.ndarray
    load_N: np.ndarray


# --- validation -------------------------------------------------------------------------------
def _as_compliance(compliance: ArrayLike, name: str = "compliance",
                   pairs_axis: bool = True) -> np.ndarray:
    c = np.asarray(compliance, dtype=float)
    if pairs_axis and c.ndim == 0:
        raise ModelError(f"`{name}` must have a last axis over the tooth pairs, was a scalar")
    if not np.all(np.isfinite(c) & (c > 0)):
        bad = c[~(np.isfinite(c) & (c > 0))].ravel()[0]
        raise ModelError(f"`{name}` must be finite and > 0 m/N, found {bad!r}")
    return c


def _as_load(load_N: ArrayLike) -> np.ndarray:
    f = np.asarray(load_N, dtype=float)
    if not np.all(np.isfinite(f) & (f >= 0)):
        bad = f[~(np.isfinite(f) & (f >= 0))].ravel()[0]
        raise ModelError(f"`load_N` must be finite and >= 0 N, found {bad!r}")
    return f


def _as_gap(gap_m: ArrayLike, name: str, allow_inf: bool) -> np.ndarray:
    g = np.asarray(gap_m, dtype=float)
    ok = ~np.isnan(g) & (np.isfinite(g) | (allow_inf & (g > 0)))
    if not np.all(ok):
        bad = g[~ok].ravel()[0]
        what = "finite or +inf (cannot touch)" if allow_inf else "finite"
        raise ModelError(f"`{name}` must be {what} (m), found {bad!r}")
    return g


# --- closed forms -----------------------------------------------------------------------------
def load_sharing_two_pairs(
    compliance_1: ArrayLike,
    compliance_2: ArrayLike,
    error_1: ArrayLike,
    error_2: ArrayLike,
    load_N: ArrayLike,
) -> LoadSharing:
    r"""Two pairs in contact: the closed form of seed 003, Eq. 6a-c (no pair is dropped).

    Parameters
    ----------
    compliance_1, compliance_2 : array_like
        Tooth-pair compliances ``C_1``, ``C_2`` (m/N), broadcastable.
    error_1, error_2 : array_like
        Profile errors (or gaps, corner contact included) ``e_1``, ``e_2`` (m).
    load_N : array_like
        Total normal load ``F`` (N), >= 0.

    Returns
    -------
    LoadSharing
        ``loads_N`` and ``in_contact`` with a last axis of length 2. A negative load means the
        pair would have to pull: use :func:`solve_load_sharing` to drop it.

    Notes
    -----
    .. math::

        x = \frac{C_1 C_2 F + C_1 e_2 + C_2 e_1}{C_1 + C_2}, \quad
        F_1 = \frac{C_2 F + e^{21}}{C_1 + C_2}, \quad F_2 = \frac{C_1 F - e^{21}}{C_1 + C_2},
        \quad e^{21} = e_2 - e_1 .

    Examples
    --------
    Equal pairs without errors share equally; an error on pair 2 shifts load to pair 1:

    >>> r = load_sharing_two_pairs(1e-9, 1e-9, 0.0, 2e-6, 4000.0)
    >>> [round(float(f)) for f in r.loads_N], round(float(r.transmission_error_m) * 1e6, 3)
    ([3000, 1000], 3.0)
    """
    c1 = _as_compliance(compliance_1, "compliance_1", pairs_axis=False)
    c2 = _as_compliance(compliance_2, "compliance_2", pairs_axis=False)
    e1 = _as_gap(error_1, "error_1", allow_inf=False)
    e2 = _as_gap(error_2, "error_2", allow_inf=False)
    f = _as_load(load_N)
    shape = np.broadcast_shapes(c1.shape, c2.shape, e1.shape, e2.shape, f.shape)
    s = c1 + c2
    e21 = e2 - e1
    x = (c1 * c2 * f + c1 * e2 + c2 * e1) / s
    f1 = (c2 * f + e21) / s
    f2 = (c1 * f - e21) / s
    loads = np.stack(np.broadcast_arrays(f1, f2), axis=-1)
    fb = np.broadcast_to(f, shape)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        lsr = np.where(fb[..., None] > 0, loads / fb[..., None], np.nan)
    return LoadSharing(np.broadcast_to(x, shape).copy(), loads, lsr,
                       np.ones(loads.shape, bool), fb.copy())


def _exclusion_products(c: np.ndarray) -> np.ndarray:
    """``prod_{q != p} c_q`` along the last axis, without division (prefix/suffix products)."""
    ones = np.ones((*c.shape[:-1], 1))
    prefix = np.concatenate([ones, np.cumprod(c[..., :-1], axis=-1)], axis=-1)
    suffix = np.concatenate([np.cumprod(c[..., :0:-1], axis=-1)[..., ::-1], ones], axis=-1)
    return np.asarray(prefix * suffix)


def load_sharing_closed_form(
    compliance: ArrayLike, error: ArrayLike, load_N: ArrayLike
) -> LoadSharing:
    r"""``n`` pairs in contact: the product closed form of seed 003, Eq. 8a-c (none dropped).

    Parameters
    ----------
    compliance : array_like
        Compliances ``C_p`` (m/N), shape ``(..., n)``, ``n >= 1``.
    error : array_like
        Profile errors or gaps ``e_p`` (m), broadcastable to ``compliance``.
    load_N : array_like
        Total load ``F`` (N), broadcastable to ``compliance.shape[:-1]``.

    Returns
    -------
    LoadSharing

    Notes
    -----
    .. math::

        x = \frac{(\prod_p C_p) F + \sum_p (\prod_{q \ne p} C_q) e_p}{\sum_p \prod_{q \ne p} C_q},
        \qquad
        F_i = \frac{(\prod_{q \ne i} C_q) F - \sum_{p} (\prod_{q \ne i, p} C_q)(e_i - e_p)}
                   {\sum_p \prod_{q \ne p} C_q}.

    The products are formed on compliances scaled by their geometric mean ``lambda`` (the form
    is homogeneous once ``F`` is scaled by ``lambda``), so many pairs do not underflow.
    """
    c = _as_compliance(compliance)
    e = np.broadcast_to(_as_gap(error, "error", allow_inf=False), c.shape)
    f = np.broadcast_to(_as_load(load_N), c.shape[:-1])
    n = c.shape[-1]
    lam = np.exp(np.mean(np.log(c), axis=-1, keepdims=True))
    cs = c / lam
    fs = f * lam[..., 0]  # F lambda: x = (prod(cs) F lambda + sum P_p e_p) / sum P_p
    p_excl = _exclusion_products(cs)  # prod_{q != p}
    den = p_excl.sum(axis=-1)
    x = (np.prod(cs, axis=-1) * fs + (p_excl * e).sum(axis=-1)) / den
    loads = np.empty(c.shape)
    for i in range(n):
        # prod_{q != i, p} cs_q for every p (the p = i term is multiplied by e_i - e_i = 0)
        others = np.delete(cs, i, axis=-1)
        pp = _exclusion_products(others) if n > 1 else np.ones((*c.shape[:-1], 0))
        eip = e[..., i : i + 1] - np.delete(e, i, axis=-1)
        # C products carry lambda^(n-2) against lambda^(n-1) in the denominator: divide by lambda
        loads[..., i] = (p_excl[..., i] * f - (pp * eip).sum(axis=-1) / lam[..., 0]) / den
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        lsr = np.where(f[..., None] > 0, loads / f[..., None], np.nan)
    return LoadSharing(x, loads, lsr, np.ones(c.shape, bool), np.array(f, float))


# --- active set -------------------------------------------------------------------------------
def solve_load_sharing(compliance: ArrayLike, gap: ArrayLike, load_N: ArrayLike) -> LoadSharing:
    r"""Loads and transmission error with the active set: pairs that would pull leave contact.

    Parameters
    ----------
    compliance : array_like
        Tooth-pair compliances ``C_i`` (m/N), shape ``(..., n)``.
    gap : array_like
        Gaps ``g_i = e_i + S_i`` (m): profile error plus separation distance (zero inside the
        theoretical path); ``+inf`` for a pair that cannot touch. Broadcastable to
        ``compliance``; every position needs at least one finite gap.
    load_N : array_like
        Total normal load ``F`` (N), >= 0, broadcastable to ``compliance.shape[:-1]``.

    Returns
    -------
    LoadSharing
        Loads are >= 0, sum to ``F`` and satisfy ``x = C_i F_i + g_i`` for every loaded pair and
        ``g_i >= x`` for every other.

    Notes
    -----
    Seed 003's procedure (Eqs. 9-17 and Tables 1-2, for any number of pairs): start with every
    pair that can touch and iterate

    .. math::

        x = \frac{F + \sum_{i \in \mathcal{A}} g_i / C_i}{\sum_{i \in \mathcal{A}} 1 / C_i},
        \qquad F_i = \frac{x - g_i}{C_i},
        \qquad \mathcal{A} \leftarrow \{ i \in \mathcal{A} : F_i > 0 \}

    until no load is non-positive (at most ``n - 1`` rounds, vectorised over positions). At
    ``F = 0`` the result is the limit ``F -> 0+``: ``x = min g``, every load zero, the pairs
    whose gap equals ``min g`` (within ``TOUCH_TOL_M``) touching, with ``LSR_i = K_i / sum K``.

    Examples
    --------
    The incoming pair of Eq. 9-10 in corner contact: its separation distance (2 um) is closed by
    the deflection of the loaded pair (4 um alone), and it takes a share:

    >>> r = solve_load_sharing([1e-9, 1e-9], [0.0, 2e-6], 4000.0)
    >>> [round(float(f)) for f in r.loads_N], round(float(r.transmission_error_m) * 1e6, 3)
    ([3000, 1000], 3.0)

    With 5 um of separation it stays out of contact (Eq. 11):

    >>> r = solve_load_sharing([1e-9, 1e-9], [0.0, 5e-6], 4000.0)
    >>> [round(float(f)) for f in r.loads_N], r.in_contact.tolist()
    ([4000, 0], [True, False])
    """
    c = _as_compliance(compliance)
    g = _as_gap(gap, "gap", allow_inf=True)
    f = _as_load(load_N)
    shape = np.broadcast_shapes(c.shape, g.shape)
    c = np.broadcast_to(c, shape)
    g = np.broadcast_to(g, shape)
    f = np.broadcast_to(f, shape[:-1]).astype(float)
    k = 1.0 / c
    can = np.isfinite(g)
    if not np.all(can.any(axis=-1)):
        raise ModelError("`gap` must be finite for at least one pair at every position "
                         "(no pair could carry the load)")
    g0 = np.where(can, g, 0.0)
    fcol = f[..., None]

    active = can.copy()
    n = shape[-1]
    x = np.zeros(shape[:-1])
    loads = np.zeros(shape)
    for _ in range(n):
        ka = np.where(active, k, 0.0)
        x = (f + (ka * g0).sum(axis=-1)) / ka.sum(axis=-1)
        loads = ka * (x[..., None] - g0)
        drop = active & (loads <= 0) & (fcol > 0)
        if not drop.any():
            break
        active &= ~drop
    loads = np.where(active, loads, 0.0)
    # x - g_i cancels digits when the gaps are large against C F: make the sum exact
    total = loads.sum(axis=-1)
    loads = loads * np.where(total > 0, f / np.where(total > 0, total, 1.0), 1.0)[..., None]

    # F = 0: the limit F -> 0+ (every load non-positive would empty the set above)
    zero = f == 0
    if np.any(zero):
        gmin = np.where(can, g, np.inf).min(axis=-1)
        touch = can & (g <= gmin[..., None] + TOUCH_TOL_M)
        x = np.where(zero, gmin, x)
        active = np.where(zero[..., None], touch, active)
        loads = np.where(zero[..., None], 0.0, loads)
    kt = np.where(active, k, 0.0)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        lsr = np.where(fcol > 0, loads / fcol, kt / kt.sum(axis=-1, keepdims=True))
    # rounding can put a lone pair's share at 1 + 1e-16
    return LoadSharing(x, loads, np.clip(lsr, 0.0, 1.0), active, f)

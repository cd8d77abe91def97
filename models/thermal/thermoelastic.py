r"""Thermoelastic mesh stiffness of a spur pair with backlash, and its critical compensation gap.

Seed 000 (FZG-C) adds two things to the elastic pair stiffness ``k_EP``: a total backlash
``c = c_1 + c_2`` on the line of action, and the thermal growth of the teeth
``Delta = Delta_1 + Delta_2`` along the line of action, which closes that backlash. A correction
factor ``chi`` (0.0285 in the seed, from coupled finite-element runs) accounts for the part of
the thermal growth that the thermoelastic coupling gives back. The thermal closure ``Delta`` is
an *input* here (m, per run or per position): computing it from temperatures is the job of the
thermal-expansion model, and its reference state (SEED-NOTES 8) is that model's choice.

Conventions
-----------
* All quantities per tooth pair, whole face width, SI: loads in N, stiffness in N/m,
  lengths in m along the line of action.
* ``Delta = Delta_1 + Delta_2`` (m): positive when the gears grow into the backlash; negative
  values (a housing that grows more than the gears) open it. Any finite value is accepted.
* ``c = c_1 + c_2 >= 0`` (m): total backlash on the line of action. The split between the
  teeth only enters the single-tooth bookkeeping values ``k'_1`` and ``k'_2``
  (``pinion_backlash_share``, half by default); the pair result does not depend on it.
* ``0 <= chi <= 1`` (-): ``chi = 1`` gives the whole thermal growth back (no thermal effect).

The model and its derivation (seed 000, "stiffness formula" section)
--------------------------------------------------------------------
The thermal load and the coupling load that the closure causes in a pair of stiffness
``k_EP`` are

.. math::

    p_e = k_{EP} \Delta, \qquad p_{te} = \chi k_{EP} \Delta,

and the elastic deflection of tooth ``i`` (single-tooth stiffness ``k_Ei``) under the normal
load ``f_n`` and these two loads is

.. math::

    \delta_{t_i} = \frac{f_n - p_e + p_{te}}{k_{E_i}}
                 = \frac{f_n - (1 - \chi) k_{EP} \Delta}{k_{E_i}} .

With its share ``c_i`` of the backlash, each tooth has the secant stiffness

.. math::

    k'_i = \frac{f_n}{\delta_{t_i} + c_i}
         = \frac{f_n k_{E_i}}{f_n - (1 - \chi) k_{EP} \Delta + c_i k_{E_i}} .

The two teeth act in series, so the compliances add; with
``1/k_E1 + 1/k_E2 = 1/k_EP`` (the definition of the pair stiffness) and ``c_1 + c_2 = c``:

.. math::

    \frac{1}{k} = \frac{1}{k'_1} + \frac{1}{k'_2}
      = \frac{\delta_{t_1} + \delta_{t_2} + c_1 + c_2}{f_n}
      = \frac{\bigl(f_n - (1 - \chi) k_{EP} \Delta\bigr)\left(\frac{1}{k_{E_1}}
        + \frac{1}{k_{E_2}}\right) + c}{f_n}
      = \frac{\frac{f_n - (1 - \chi) k_{EP} \Delta}{k_{EP}} + c}{f_n},

.. math::

    k = \frac{f_n}{\dfrac{f_n - (1 - \chi) k_{EP} \Delta}{k_{EP}} + c}
      = \frac{f_n k_{EP}}{f_n - (1 - \chi) k_{EP} \Delta + c\, k_{EP}} .
    \qquad (1)

**SEED-NOTES 7.** The seed's "k_elastic" formula (after Table 4) writes the last term as
``c k_E``. The series combination above gives ``c k_EP`` exactly, whatever the split of ``c``
between the teeth; ``c k_E`` would need ``k_E = k_EP``, which no single tooth has
(``k_E1, k_E2 > k_EP``). The seed's own pair formula and its ``k_coupling`` (before Table 5)
agree with ``c k_EP``. Eq. (1) with ``c k_EP`` is implemented; ``tests/models/
test_thermoelastic.py`` repeats the derivation numerically and shows that ``c k_E1``, ``c k_E2``
or their mean do not reproduce the series combination.

**Elastic stiffness with backlash** (Table 4, "chi and Delta absent"): ``Delta = 0`` in (1),

.. math:: k_{el} = \frac{f_n k_{EP}}{f_n + c\, k_{EP}} , \qquad (2)

load independent (``= k_EP``) only at ``c = 0`` (the seed's 381.96 and 477.45 N m give the same
stiffness), otherwise rising with load towards ``k_EP``, and falling as ``c`` grows.

What the stiffness measures
---------------------------
The denominator of (1) divided by ``k_EP`` is the seed's normal deformation

.. math:: \delta_n = \frac{f_n}{k_{EP}} + c - (1 - \chi)\Delta ,

the travel of the loaded drive flank along the line of action counted from the position where
the back flank just touches: the free play ``c``, less the thermal closure, plus the elastic
deflection. ``k = f_n / delta_n`` is a secant stiffness through that origin.

The critical compensation gap (seed 000, "critical compensation gap ~ 10 um")
------------------------------------------------------------------------------
Write ``c* = (1 - chi) Delta`` and ``g = k_EP (c - c*)``; then (1) is

.. math:: k = \frac{f_n k_{EP}}{f_n + g} = \frac{k_{EP}}{1 + g / f_n} .

The thermoelastic stiffness equals the zero-backlash elastic stiffness ``k_EP`` (Eq. 2 at
``c = 0``) when

.. math::

    \frac{f_n k_{EP}}{f_n + g} = k_{EP}
    \iff f_n + g = f_n \iff k_{EP}\,(c - (1 - \chi)\Delta) = 0
    \iff c = c^* = (1 - \chi)(\Delta_1 + \Delta_2),

independent of the load ``f_n`` and of ``k_EP`` (so of the position on the path, when
``Delta`` is the same along the path). If ``Delta`` varies along the path, ``c*`` is a
function of position, and no single backlash makes the *mean* mesh stiffness exactly load
independent (:func:`critical_gap_numerical` then finds a load-dependent root).
:func:`critical_gap_numerical` finds the gap by root finding on ``k(c) - k_EP`` at several
loads, as an independent check of the closed form.

The three regimes (Table 5)
---------------------------
.. math::

    \frac{\partial k}{\partial f_n} = \frac{k_{EP}\, g}{(f_n + g)^2}, \qquad
    \frac{\partial k}{\partial c} = -\frac{k_{EP}^2 f_n}{(f_n + g)^2} < 0, \qquad
    \lim_{f_n \to \infty} k = k_{EP} .

* ``c < c*`` (``g < 0``): ``k > k_EP`` and the stiffness *falls* with load, towards ``k_EP``;
  defined only for ``f_n > -g`` (see validity below);
* ``c = c*``: ``k = k_EP`` at every load (unchanged);
* ``c > c*`` (``g > 0``): ``0 < k < k_EP``, the stiffness *rises* with load and saturates at
  ``k_EP``.

At every load the stiffness falls as the backlash grows (``dk/dc < 0``). Limits: ``c = 0`` and
``Delta = 0`` give ``k = k_EP``; ``Delta = 0`` or ``chi = 1`` give ``c* = 0`` and Eq. (2).
:func:`stiffness_regime` returns the sign of ``c - c*``.

Validity: the jammed state (SEED-NOTES 10)
------------------------------------------
The denominator of (1), ``D = f_n - (1 - chi) k_EP Delta + c k_EP = f_n + g``, reaches zero
at ``f_n = k_EP (c* - c)``: whenever the thermal closure exceeds the backlash
(interference ``i = c* - c > 0``) and the load is below ``k_EP i``. Eq. (1) then returns an
infinite, then negative, stiffness. The state is the gears *jammed by thermal growth*: with
the drive-flank pair stiffness ``k_d`` and back-flank pair stiffness ``k_b``, both flanks in
contact share the interference, ``delta_d + delta_b = i``, and carry ``k_d delta_d - k_b
delta_b = f_n``:

.. math::

    \delta_d = \frac{f_n + k_b i}{k_d + k_b}, \qquad
    \delta_b = \frac{k_d i - f_n}{k_d + k_b} ,

so the back flank stays loaded (``delta_b > 0``) exactly while ``f_n < k_d i``, i.e. exactly
while ``D < 0`` for ``k_d = k_EP``, whatever ``k_b``. At ``D = 0`` the back flank lifts off,
and beyond it Eq. (1) applies. :func:`double_flank_contact` solves this two-flank model; its
tangent stiffness is ``k_d + k_b`` in double-flank contact and ``k_d`` in single-flank
contact. Eq. (1), a secant through the back-flank touch position, has no meaning there.

What the code does with it:

* scalar API (:func:`thermoelastic_pair_stiffness`): raises :class:`ThermalJamError` (a
  :class:`~models.errors.ModelError`, so a ``ValueError``) carrying the load, ``k_EP``, the
  critical gap and the backlash;
* vectorised API (:func:`thermoelastic_stiffness`, :func:`thermoelastic_mesh_stiffness`):
  the result carries ``jammed`` (bool, ``D <= 0``) and puts the stand-in
  :data:`JAMMED_STAND_IN` (NaN) into ``k_N_per_m`` there, never a negative or infinite value.
  It also carries ``net_deflection_m`` (``delta_n = D / k_EP``; ``<= 0`` where jammed, its
  magnitude the depth of the jam) and offers ``k_double_flank_N_per_m``, the double-flank
  tangent stiffness ``2 k_EP`` (back-flank pair taken as stiff as the drive-flank pair: the
  back-flank path of contact is the mirror image of the drive-flank one, so its cycle mean is
  the same) where jammed and Eq. (1) elsewhere.

For a calibration likelihood that stays finite and honest, use the mask rather than the NaN:
either (a) treat the jammed state as outside the seed's model, i.e. give such parameter
draws zero likelihood for that run, or a soft penalty growing with ``-net_deflection_m``
(finite, continuous at the boundary, and visible in the diagnostics); or (b) model the
jammed runs with the double-flank tangent stiffness as a separate state. The two stiffness
definitions do not join at ``D = 0`` (the secant diverges there, the tangent is ``2 k_EP``),
so (b) is a different model, not a continuation; report which one was used. Never replace
the NaN by an arbitrary finite stiffness.

References
----------
.. [1] Seed 000, "Thermoelastic coupling stiffness analysis of spur gears with consideration
   of backlash" (FZG-C): stiffness formula, Tables 4-5, critical compensation gap.
.. [2] A. Kahraman, R. Singh, "Non-linear dynamics of a spur gear pair", J. Sound Vib. 142
   (1990) 49-75 (backlash as a clearance in the mesh spring; double-sided contact).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final, Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq

from models.errors import ModelError
from models.geometry.gear_pair import GearPair
from models.stiffness.ishikawa import HertzOption, tooth_pair_stiffness
from models.stiffness.load_distribution import (
    contact_path_positions,
    load_share_seed_000,
    normal_load_from_torque,
)
from models.thermal.checks import as_backlash, as_chi, as_closure, as_nonnegative, as_positive

__all__ = [
    "CRITICAL_GAP_ATOL_M",
    "FALLS",
    "JAMMED_STAND_IN",
    "RISES",
    "SEED_000_CHI",
    "UNCHANGED",
    "CriticalGapSearch",
    "DoubleFlankContact",
    "ThermalJamError",
    "ThermoelasticStiffness",
    "critical_gap",
    "critical_gap_numerical",
    "double_flank_contact",
    "elastic_backlash_stiffness",
    "stiffness_regime",
    "thermoelastic_mesh_stiffness",
    "thermoelastic_pair_stiffness",
    "thermoelastic_stiffness",
]

#: The seed's thermoelastic coupling correction factor chi (-), averaged over the mesh cycle.
SEED_000_CHI: Final[float] = 0.0285
#: The value put into a stiffness where the gears are jammed (see the module notes).
JAMMED_STAND_IN: Final[float] = math.nan
#: ``|c - c*|`` up to which a backlash counts as the critical gap (m): 1 pm, round-off of
#: ``c*`` computed from a closure in metres.
CRITICAL_GAP_ATOL_M: Final[float] = 1e-12
#: Regime codes of :func:`stiffness_regime` (Table 5): stiffness falls with load ...
FALLS: Final[int] = -1
#: ... is unchanged (c = c*) ...
UNCHANGED: Final[int] = 0
#: ... rises with load and saturates at k_EP.
RISES: Final[int] = 1


# --- the error -----------------------------------------------------------------------------
class ThermalJamError(ModelError):
    """The gears are jammed by thermal growth: Eq. (1)'s denominator is ``<= 0``.

    Attributes
    ----------
    normal_load_N : float
        Normal load on the pair (N).
    k_EP_N_per_m : float
        Elastic pair stiffness (N/m).
    critical_gap_m : float
        ``c* = (1 - chi) Delta`` (m).
    backlash_m : float
        Total backlash ``c`` (m).
    """

    def __init__(self, normal_load_N: float, k_EP_N_per_m: float, critical_gap_m: float,
                 backlash_m: float) -> None:
        self.normal_load_N = float(normal_load_N)
        self.k_EP_N_per_m = float(k_EP_N_per_m)
        self.critical_gap_m = float(critical_gap_m)
        self.backlash_m = float(backlash_m)
        super().__init__(str(self))

    @property
    def interference_m(self) -> float:
        """Thermal interference ``c* - c`` (m), > 0 when jammed."""
        return self.critical_gap_m - self.backlash_m

    @property
    def net_deflection_m(self) -> float:
        """``f_n / k_EP + c - c*`` (m), <= 0 when jammed."""
        return self.normal_load_N / self.k_EP_N_per_m - self.interference_m

    def __str__(self) -> str:
        return (
            f"gears jammed by thermal growth: backlash `c` = {self.backlash_m * 1e6:.4g} um is "
            f"below the thermal closure (1 - chi)(Delta_1 + Delta_2) = "
            f"{self.critical_gap_m * 1e6:.4g} um by {self.interference_m * 1e6:.4g} um, more than "
            f"the elastic deflection f_n / k_EP = "
            f"{self.normal_load_N / self.k_EP_N_per_m * 1e6:.4g} um (f_n = "
            f"{self.normal_load_N:.6g} N): both flanks are in contact and the thermoelastic "
            f"stiffness is undefined"
        )

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.normal_load_N, self.k_EP_N_per_m, self.critical_gap_m,
                             self.backlash_m))


# --- validation at the boundary ------------------------------------------------------------
def _as_share(value: float) -> float:
    v = float(value)
    if not 0.0 <= v <= 1.0:
        raise ModelError(f"`pinion_backlash_share` must lie in [0, 1], was {value!r}")
    return v


def _scalar(name: str, value: float) -> float:
    a = np.asarray(value, dtype=float)
    if a.size != 1:
        raise ModelError(f"`{name}` must be a scalar in the scalar API, was an array of shape "
                         f"{a.shape}; use thermoelastic_stiffness for arrays")
    return float(a.reshape(()))


# --- closed forms --------------------------------------------------------------------------
def critical_gap(thermal_closure_m: ArrayLike, chi: ArrayLike = SEED_000_CHI) -> np.ndarray:
    r"""Critical compensation gap ``c* = (1 - chi)(Delta_1 + Delta_2)`` (m).

    The backlash at which the thermoelastic stiffness (1) equals the zero-backlash elastic
    stiffness ``k_EP`` at every load (derivation in the module notes).

    Parameters
    ----------
    thermal_closure_m : array_like
        ``Delta = Delta_1 + Delta_2`` along the line of action (m).
    chi : array_like
        Thermoelastic coupling correction factor (-), in [0, 1]; the seed's 0.0285 by default.

    Returns
    -------
    numpy.ndarray
        ``c*`` (m), the broadcast shape of the inputs. Negative when ``Delta < 0`` (no
        backlash compensates a thermal opening).

    Examples
    --------
    >>> round(float(critical_gap(10.2934e-6)) * 1e6, 3)   # um, chi = 0.0285
    10.0
    """
    return (1.0 - as_chi(chi)) * as_closure(thermal_closure_m)


def elastic_backlash_stiffness(normal_load_N: ArrayLike, k_EP_N_per_m: ArrayLike,
                               backlash_m: ArrayLike) -> np.ndarray:
    r"""Elastic pair stiffness with backlash, no thermal closure: Eq. (2) (N/m).

    .. math:: k_{el} = \frac{f_n k_{EP}}{f_n + c\, k_{EP}}

    Parameters
    ----------
    normal_load_N : array_like
        Normal load on the pair ``f_n = f'_n R`` (N), > 0.
    k_EP_N_per_m : array_like
        Elastic pair stiffness (N/m), > 0.
    backlash_m : array_like
        Total backlash ``c`` (m), >= 0.

    Returns
    -------
    numpy.ndarray
        ``k_el`` (N/m), broadcast shape; equal to ``k_EP`` at ``c = 0``, rising with load.

    Examples
    --------
    >>> float(elastic_backlash_stiffness(1e3, 4e8, 0.0)) == 4e8
    True
    >>> round(float(elastic_backlash_stiffness(1e3, 4e8, 2.5e-6)) / 4e8, 3)
    0.5
    """
    f = as_positive("normal_load_N", normal_load_N)
    k = as_positive("k_EP_N_per_m", k_EP_N_per_m)
    c = as_backlash(backlash_m)
    return np.asarray(f * k / (f + c * k))


def thermoelastic_pair_stiffness(
    normal_load_N: float,
    k_EP_N_per_m: float,
    thermal_closure_m: float,
    backlash_m: float,
    chi: float = SEED_000_CHI,
) -> float:
    r"""Thermoelastic pair stiffness with backlash, Eq. (1), for one set of scalars (N/m).

    .. math::

        k = \frac{f_n k_{EP}}{f_n - (1 - \chi) k_{EP} (\Delta_1 + \Delta_2) + c\, k_{EP}}

    Parameters
    ----------
    normal_load_N : float
        Normal load on the pair (N), > 0.
    k_EP_N_per_m : float
        Elastic pair stiffness (N/m), > 0.
    thermal_closure_m : float
        ``Delta_1 + Delta_2`` (m).
    backlash_m : float
        Total backlash ``c`` (m), >= 0.
    chi : float
        Correction factor (-), in [0, 1].

    Returns
    -------
    float
        ``k`` (N/m), finite and > 0.

    Raises
    ------
    ThermalJamError
        The denominator is ``<= 0``: the gears are jammed by thermal growth (module notes).
    ModelError
        An argument out of range or not a scalar.

    Examples
    --------
    Backlash equal to the critical gap: the stiffness is ``k_EP`` at any load.

    >>> d, chi = 10e-6, 0.0285
    >>> c = (1 - chi) * d
    >>> [round(thermoelastic_pair_stiffness(f, 4e8, d, c, chi) / 4e8, 12) for f in (1e3, 1e4)]
    [1.0, 1.0]
    """
    f = float(as_positive("normal_load_N", _scalar("normal_load_N", normal_load_N)))
    k = float(as_positive("k_EP_N_per_m", _scalar("k_EP_N_per_m", k_EP_N_per_m)))
    d = float(as_closure(_scalar("thermal_closure_m", thermal_closure_m)))
    c = float(as_backlash(_scalar("backlash_m", backlash_m)))
    x = float(as_chi(_scalar("chi", chi)))
    c_star = (1.0 - x) * d
    den = f - (1.0 - x) * k * d + c * k
    if not den > 0.0:
        raise ThermalJamError(f, k, c_star, c)
    return f * k / den


# --- vectorised ----------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class ThermoelasticStiffness:
    """Thermoelastic stiffness of a tooth pair with backlash, term by term (seed 000).

    All arrays share one broadcast shape: the parameters' shape, with positions along the
    path on the last axis when computed by :func:`thermoelastic_mesh_stiffness`.

    Attributes
    ----------
    s_m : numpy.ndarray
        Positions on the line of action from T1 (m); empty when no positions were given.
    normal_load_N : numpy.ndarray
        ``f_n = f'_n R(theta)`` (N).
    k_E1_N_per_m, k_E2_N_per_m : numpy.ndarray
        Single-tooth elastic stiffness of pinion and wheel tooth (N/m).
    k_EP_N_per_m : numpy.ndarray
        Elastic pair stiffness ``k_E1 k_E2 / (k_E1 + k_E2)`` (N/m).
    thermal_closure_m : numpy.ndarray
        ``Delta = Delta_1 + Delta_2`` (m).
    backlash_m : numpy.ndarray
        Total backlash ``c`` (m).
    chi : numpy.ndarray
        Correction factor (-).
    critical_gap_m : numpy.ndarray
        ``c* = (1 - chi) Delta`` (m).
    thermal_load_N, coupling_load_N : numpy.ndarray
        ``p_e = k_EP Delta`` and ``p_te = chi k_EP Delta`` (N).
    delta_t1_m, delta_t2_m : numpy.ndarray
        Elastic deflections ``(f_n - (1 - chi) k_EP Delta) / k_Ei`` (m); negative where the
        thermal interference outweighs the load.
    k1_prime_N_per_m, k2_prime_N_per_m : numpy.ndarray
        Single-tooth thermoelastic stiffness ``k'_i = f_n / (delta_ti + c_i)`` (N/m), with
        ``c_1 = share c``; :data:`JAMMED_STAND_IN` where ``delta_ti + c_i <= 0`` (the split of
        the backlash between the teeth is bookkeeping; only the pair value is physical).
    k_N_per_m : numpy.ndarray
        Pair stiffness, Eq. (1) (N/m); :data:`JAMMED_STAND_IN` (NaN) where ``jammed``.
    k_elastic_N_per_m : numpy.ndarray
        Elastic stiffness with the same backlash and no thermal closure, Eq. (2) (N/m).
    net_deflection_m : numpy.ndarray
        ``delta_n = f_n / k_EP + c - c*`` (m), Eq. (1)'s denominator over ``k_EP``; ``<= 0``
        where jammed, its magnitude the depth of the jam (for a penalty).
    jammed : numpy.ndarray
        Bool, ``net_deflection_m <= 0``: both flanks in contact, Eq. (1) undefined.
    pinion_backlash_share : float
        ``c_1 / c``.
    """

    s_m: np.ndarray
    normal_load_N: np.ndarray
    k_E1_N_per_m: np.ndarray
    k_E2_N_per_m: np.ndarray
    k_EP_N_per_m: np.ndarray
    thermal_closure_m: np.ndarray
    backlash_m: np.ndarray
    chi: np.ndarray
    critical_gap_m: np.ndarray
    thermal_load_N: np.ndarray
    coupling_load_N: np.ndarray
    delta_t1_m: np.ndarray
    delta_t2_m: np.ndarray
    k1_prime_N_per_m: np.ndarray
    k2_prime_N_per_m: np.ndarray
    k_N_per_m: np.ndarray
    k_elastic_N_per_m: np.ndarray
    net_deflection_m: np.ndarray
    jammed: np.ndarray
    pinion_backlash_share: float

    @property
    def any_jammed(self) -> bool:
        """True if any entry is jammed."""
        return bool(np.any(self.jammed))

    @property
    def k_double_flank_N_per_m(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """Eq. (1) where valid, the double-flank tangent stiffness ``2 k_EP`` where jammed (N/m).

        A separate model of the jammed state (module notes), not a continuation of Eq. (1).
        """
        return np.where(self.jammed, 2.0 * self.k_EP_N_per_m, self.k_N_per_m)

    def raise_if_jammed(self) -> None:
        """Raise :class:`ThermalJamError` for the first jammed entry, if any."""
        if self.any_jammed:
            i = np.flatnonzero(self.jammed.ravel())[0]
            raise ThermalJamError(
                float(self.normal_load_N.ravel()[i]), float(self.k_EP_N_per_m.ravel()[i]),
                float(self.critical_gap_m.ravel()[i]), float(self.backlash_m.ravel()[i]))


def thermoelastic_stiffness(
    normal_load_N: ArrayLike,
    k_E1_N_per_m: ArrayLike,
    k_E2_N_per_m: ArrayLike,
    thermal_closure_m: ArrayLike,
    backlash_m: ArrayLike,
    chi: ArrayLike = SEED_000_CHI,
    *,
    pinion_backlash_share: float = 0.5,
    s_m: ArrayLike | None = None,
) -> ThermoelasticStiffness:
    r"""Thermoelastic stiffness of tooth pairs with backlash, vectorised (seed 000, Eq. 1).

    .. math::

        \delta_{t_i} = \frac{f_n - (1 - \chi) k_{EP} \Delta}{k_{E_i}}, \quad
        k'_i = \frac{f_n k_{E_i}}{f_n - (1 - \chi) k_{EP} \Delta + c_i k_{E_i}}, \quad
        k = \frac{f_n k_{EP}}{f_n - (1 - \chi) k_{EP} \Delta + c\, k_{EP}}

    with ``k_EP = k_E1 k_E2 / (k_E1 + k_E2)``; derivation and validity in the module notes.

    Parameters
    ----------
    normal_load_N : array_like
        Normal load on the pair ``f_n`` (N), > 0.
    k_E1_N_per_m, k_E2_N_per_m : array_like
        Single-tooth elastic stiffness of the pinion and wheel tooth (N/m), > 0.
    thermal_closure_m : array_like
        ``Delta = Delta_1 + Delta_2`` (m), finite.
    backlash_m : array_like
        Total backlash ``c`` (m), >= 0.
    chi : array_like
        Correction factor (-), in [0, 1].
    pinion_backlash_share : float
        ``c_1 / c`` for the single-tooth values (the pair value does not depend on it).
    s_m : array_like, optional
        Positions the loads belong to (m from T1), stored in the result only.

    Returns
    -------
    ThermoelasticStiffness
        Jammed entries (Eq. 1's denominator ``<= 0``) carry ``jammed = True`` and NaN
        stiffness; nothing is ever negative or infinite.

    Examples
    --------
    >>> r = thermoelastic_stiffness([500.0, 5e3], 8e8, 8e8, 10e-6, 2e-6)
    >>> r.jammed.tolist(), bool(r.k_N_per_m[1] > 4e8)
    ([True, False], True)
    """
    f = as_positive("normal_load_N", normal_load_N)
    k1 = as_positive("k_E1_N_per_m", k_E1_N_per_m)
    k2 = as_positive("k_E2_N_per_m", k_E2_N_per_m)
    d = as_closure(thermal_closure_m)
    c = as_backlash(backlash_m)
    x = as_chi(chi)
    share = _as_share(pinion_backlash_share)
    f, k1, k2, d, c, x = np.broadcast_arrays(f, k1, k2, d, c, x)
    kp = k1 * k2 / (k1 + k2)
    c_star = (1.0 - x) * d
    p_e = kp * d
    p_te = x * p_e
    closure_load = f - p_e + p_te  # f_n - (1 - chi) k_EP Delta
    net = f / kp + (c - c_star)  # Eq. (1)'s denominator / k_EP
    jammed = net <= 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(jammed, JAMMED_STAND_IN, f / net)
        d1, d2 = closure_load / k1, closure_load / k2
        den1, den2 = d1 + share * c, d2 + (1.0 - share) * c
        kp1 = np.where(den1 > 0, f / den1, JAMMED_STAND_IN)
        kp2 = np.where(den2 > 0, f / den2, JAMMED_STAND_IN)
    s = np.empty(0) if s_m is None else np.asarray(s_m, dtype=float)
    return ThermoelasticStiffness(
        s_m=s, normal_load_N=f.copy(), k_E1_N_per_m=k1.copy(), k_E2_N_per_m=k2.copy(),
        k_EP_N_per_m=kp, thermal_closure_m=d.copy(), backlash_m=c.copy(), chi=x.copy(),
        critical_gap_m=c_star, thermal_load_N=p_e, coupling_load_N=p_te, delta_t1_m=d1,
        delta_t2_m=d2, k1_prime_N_per_m=kp1, k2_prime_N_per_m=kp2, k_N_per_m=k,
        k_elastic_N_per_m=f * kp / (f + c * kp), net_deflection_m=net, jammed=jammed,
        pinion_backlash_share=share,
    )


def thermoelastic_mesh_stiffness(
    pair: GearPair,
    torque_Nm: ArrayLike,
    thermal_closure_m: ArrayLike,
    backlash_m: ArrayLike,
    chi: ArrayLike = SEED_000_CHI,
    *,
    s_m: ArrayLike | None = None,
    closure_along_path: bool = False,
    include_hertz: HertzOption = False,
    shear_coefficient: float = 1.0,
    anchor: Literal["form", "base"] = "form",
    pinion_backlash_share: float = 0.5,
) -> ThermoelasticStiffness:
    r"""Thermoelastic pair stiffness along the path of contact for a pinion torque (seed 000).

    The load at each position is the seed's ``f_n = f'_n R(theta)``, with the exact total
    normal load ``f'_n = T / r_b1`` (SEED-NOTES 5; :func:`~models.stiffness.normal_load_from_
    torque`) and the load share of :func:`~models.stiffness.load_share_seed_000`; the
    single-tooth stiffnesses are Ishikawa's (:func:`~models.stiffness.tooth_pair_stiffness`,
    no contact term by default, as the seed). Then :func:`thermoelastic_stiffness`.

    Parameters
    ----------
    pair : GearPair
    torque_Nm : array_like
        Pinion torque (N m), > 0; shape ``P`` (runs, samples, ...).
    thermal_closure_m : array_like
        ``Delta_1 + Delta_2`` (m). Broadcasts with ``P`` (uniform along the path), or, with
        ``closure_along_path=True``, has the positions on its last axis.
    backlash_m : array_like
        Total backlash (m), broadcasts with ``P``.
    chi : array_like
        Correction factor (-), broadcasts with ``P``.
    s_m : array_like, optional
        Positions on the path of contact (m from T1), 1-D; default the seed's 52 points A..E.
    closure_along_path : bool
        See ``thermal_closure_m``.
    include_hertz, shear_coefficient, anchor
        Options of :func:`~models.stiffness.ishikawa_deflection`; ``"weber"`` is evaluated
        at each position's load.
    pinion_backlash_share : float
        See :func:`thermoelastic_stiffness`.

    Returns
    -------
    ThermoelasticStiffness
        Shape ``P + (n_positions,)``.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> r = thermoelastic_mesh_stiffness(g, [381.96, 477.45], 0.0, 0.0)
    >>> r.k_N_per_m.shape, bool(np.allclose(r.k_N_per_m[0], r.k_N_per_m[1], rtol=1e-14))
    ((2, 52), True)
    """
    s = contact_path_positions(pair) if s_m is None else np.asarray(s_m, dtype=float)
    if s.ndim != 1:
        raise ModelError(f"`s_m` must be 1-D, had shape {s.shape}")
    t = as_positive("torque_Nm", torque_Nm)
    share_R = load_share_seed_000(pair, s)
    if np.any(share_R <= 0):
        raise ModelError("`s_m` must lie on the path of contact (load share R > 0)")
    f = normal_load_from_torque(pair, t)[..., None] * share_R
    weber = include_hertz == "weber"
    ks = tooth_pair_stiffness(pair, s, load_N=f if weber else 1.0, include_hertz=include_hertz,
                              shear_coefficient=shear_coefficient, anchor=anchor)
    d = as_closure(thermal_closure_m)
    if closure_along_path:
        if d.ndim == 0 or d.shape[-1] != s.size:
            raise ModelError(f"`thermal_closure_m` must have the {s.size} positions on its last "
                             f"axis with closure_along_path=True, had shape {d.shape}")
    else:
        d = d[..., None]
    return thermoelastic_stiffness(
        f, ks.k_E1_N_per_m, ks.k_E2_N_per_m, d, np.asarray(backlash_m, dtype=float)[..., None],
        np.asarray(chi, dtype=float)[..., None], pinion_backlash_share=pinion_backlash_share,
        s_m=s,
    )


# --- regimes and the numerical critical gap ------------------------------------------------
def stiffness_regime(
    backlash_m: ArrayLike,
    thermal_closure_m: ArrayLike,
    chi: ArrayLike = SEED_000_CHI,
    *,
    atol_m: float = CRITICAL_GAP_ATOL_M,
) -> np.ndarray:
    r"""Table 5's regime: how the thermoelastic stiffness changes as the load grows.

    .. math:: \operatorname{sign} \frac{\partial k}{\partial f_n} = \operatorname{sign}(c - c^*),
        \qquad c^* = (1 - \chi)(\Delta_1 + \Delta_2)

    Parameters
    ----------
    backlash_m : array_like
        Total backlash ``c`` (m), >= 0.
    thermal_closure_m : array_like
        ``Delta_1 + Delta_2`` (m).
    chi : array_like
        Correction factor (-), in [0, 1].
    atol_m : float
        ``|c - c*| <= atol_m`` counts as ``c = c*`` (default 1 pm: round-off of
        ``(1 - chi) Delta``, far below any measurable backlash).

    Returns
    -------
    numpy.ndarray
        int8, broadcast shape: :data:`FALLS` (-1, ``c < c*``: stiffness above ``k_EP``,
        falling towards it; undefined at loads below ``k_EP (c* - c)``), :data:`UNCHANGED`
        (0, ``c = c*``: ``k = k_EP`` at every load) or :data:`RISES` (+1, ``c > c*``: below
        ``k_EP``, rising and saturating at it).

    Examples
    --------
    >>> stiffness_regime([0.0, 9.715e-6, 40e-6], 10e-6, 0.0285).tolist()
    [-1, 0, 1]
    """
    if not (math.isfinite(atol_m) and atol_m >= 0):
        raise ModelError(f"`atol_m` must be finite and >= 0, was {atol_m!r}")
    diff = as_backlash(backlash_m) - critical_gap(thermal_closure_m, chi)
    out = np.where(np.abs(diff) <= atol_m, UNCHANGED, np.sign(diff))
    return np.asarray(out, dtype=np.int8)


@dataclass(frozen=True)
class CriticalGapSearch:
    """The critical compensation gap found by root finding, one root per load.

    Attributes
    ----------
    normal_load_N : numpy.ndarray
        Total normal loads ``f'_n`` searched at (N), shape ``(n_loads,)``.
    gap_m : numpy.ndarray
        The backlash at which the (path-averaged) thermoelastic stiffness equals the
        zero-backlash elastic one at that load (m).
    closed_form_m : float
        ``(1 - chi) Delta`` when the closure is uniform along the path, else NaN (no
        load-independent gap exists then).
    """

    normal_load_N: np.ndarray
    gap_m: np.ndarray
    closed_form_m: float

    @property
    def spread_m(self) -> float:
        """``max - min`` of the roots over the loads (m): zero when the gap is load independent."""
        return float(np.ptp(self.gap_m))


def critical_gap_numerical(
    k_EP_N_per_m: ArrayLike,
    thermal_closure_m: ArrayLike,
    chi: float,
    normal_loads_N: ArrayLike,
    *,
    load_share: ArrayLike = 1.0,
    weights: ArrayLike | None = None,
) -> CriticalGapSearch:
    r"""Critical gap by root finding on the stiffness difference, at each of several loads.

    For each total load ``F`` solve for ``c``

    .. math::

        h(c) = \sum_j w_j \frac{f_j k_{EP,j}}{f_j - (1 - \chi) k_{EP,j} \Delta_j + c\, k_{EP,j}}
               - \sum_j w_j k_{EP,j} = 0, \qquad f_j = F R_j,

    by Brent's method (:func:`scipy.optimize.brentq`): with one position it is Eq. (1) minus
    ``k_EP``; with positions and quadrature weights it is the path-averaged (mean mesh)
    stiffness minus the elastic one. ``h`` falls monotonically from ``+inf`` at the edge of
    the jammed region, ``c_lo = max_j (c*_j - f_j / k_EP,j)``, to ``-sum w k_EP``; the bracket
    starts just above ``c_lo`` and doubles upward until ``h < 0``. This uses the model's
    domain, not the closed form, so it checks :func:`critical_gap` independently.

    Parameters
    ----------
    k_EP_N_per_m : array_like
        Elastic pair stiffness at the positions (N/m), 1-D or scalar.
    thermal_closure_m : array_like
        ``Delta`` at the positions (m), broadcasts with ``k_EP_N_per_m``.
    chi : float
        Correction factor (-).
    normal_loads_N : array_like
        Total normal loads ``F`` (N), 1-D.
    load_share : array_like
        ``R_j`` at the positions (-), default 1.
    weights : array_like, optional
        Quadrature weights ``w_j`` (default equal).

    Returns
    -------
    CriticalGapSearch
        A root below zero means no physical backlash compensates (a thermal opening).

    Examples
    --------
    >>> r = critical_gap_numerical(4e8, 10e-6, 0.0285, [1e3, 1e4, 1e5])
    >>> [round(float(g) * 1e6, 9) for g in r.gap_m]
    [9.715, 9.715, 9.715]
    """
    k = as_positive("k_EP_N_per_m", k_EP_N_per_m)
    d = as_closure(thermal_closure_m)
    x = float(as_chi(chi))
    share = as_positive("load_share", load_share)
    k, d, share = (np.atleast_1d(a).astype(float) for a in np.broadcast_arrays(k, d, share))
    if k.ndim != 1:
        raise ModelError(f"`k_EP_N_per_m` must be 1-D along the path, had shape {k.shape}")
    w = np.full(k.shape, 1.0 / k.size) if weights is None else \
        np.broadcast_to(as_positive("weights", weights), k.shape).astype(float)
    loads = np.atleast_1d(as_positive("normal_loads_N", normal_loads_N)).astype(float)
    if loads.ndim != 1:
        raise ModelError(f"`normal_loads_N` must be 1-D, had shape {loads.shape}")
    c_star = (1.0 - x) * d
    target = float(np.sum(w * k))
    gaps = np.empty(loads.size)
    for n, big_f in enumerate(loads):
        f = big_f * share

        def h(c: float, f: np.ndarray = f) -> float:
            return float(np.sum(w * f * k / (f + k * (c - c_star)))) - target

        scale = float(np.max(f / k))
        lo = float(np.max(c_star - f / k))
        lo += 1e-9 * scale + 1e-300
        while not h(lo) > 0:  # too close to the pole for round-off: step off it
            lo += 1e-6 * scale
        step = scale + abs(lo)
        hi = lo + step
        while h(hi) >= 0:
            step *= 2.0
            hi = lo + step
        gaps[n] = brentq(h, lo, hi, xtol=1e-22, rtol=8.9e-16, maxiter=500)
    uniform = bool(np.ptp(d) == 0.0)
    return CriticalGapSearch(loads, gaps, float(c_star[0]) if uniform else math.nan)


# --- the jammed state as contact on both flanks --------------------------------------------
@dataclass(frozen=True)
class DoubleFlankContact:
    """Loads and stiffness of a pair with thermal interference, both flanks allowed to touch.

    Attributes
    ----------
    normal_load_N : numpy.ndarray
        Transmitted load ``f_n = F_d - F_b`` (N).
    interference_m : numpy.ndarray
        ``i = c* - c`` (m); ``<= 0`` means free play, never double-flank contact.
    drive_deflection_m, back_deflection_m : numpy.ndarray
        Elastic approach of the drive-flank and back-flank pairs (m), >= 0.
    drive_load_N, back_load_N : numpy.ndarray
        Contact loads ``k_d delta_d`` and ``k_b delta_b`` (N).
    double_flank : numpy.ndarray
        Bool, the back flank carries load: ``f_n < k_d i``, the jammed state of Eq. (1).
    tangent_stiffness_N_per_m : numpy.ndarray
        ``d f_n / d x``: ``k_d + k_b`` in double-flank contact, ``k_d`` otherwise (N/m).
    """

    normal_load_N: np.ndarray
    interference_m: np.ndarray
    drive_deflection_m: np.ndarray
    back_deflection_m: np.ndarray
    drive_load_N: np.ndarray
    back_load_N: np.ndarray
    double_flank: np.ndarray
    tangent_stiffness_N_per_m: np.ndarray


def double_flank_contact(
    normal_load_N: ArrayLike,
    k_EP_N_per_m: ArrayLike,
    interference_m: ArrayLike,
    *,
    k_back_N_per_m: ArrayLike | None = None,
) -> DoubleFlankContact:
    r"""Two-flank contact model of the jammed state: the pair squeezed by thermal interference.

    Drive flank (stiffness ``k_d = k_EP``) and back flank (``k_b``, default ``k_EP``) are
    springs in parallel sharing the interference ``i``; compatibility and equilibrium

    .. math::

        \delta_d + \delta_b = i, \qquad k_d \delta_d - k_b \delta_b = f_n
        \;\Rightarrow\;
        \delta_d = \frac{f_n + k_b i}{k_d + k_b}, \quad
        \delta_b = \frac{k_d i - f_n}{k_d + k_b}

    while ``delta_b > 0``, i.e. ``f_n < k_d i`` (the back flank lifts off exactly where
    Eq. (1)'s denominator crosses zero, whatever ``k_b``); otherwise single-flank contact,
    ``delta_d = f_n / k_d``, ``delta_b = 0``.

    Parameters
    ----------
    normal_load_N : array_like
        Transmitted normal load (N), >= 0.
    k_EP_N_per_m : array_like
        Drive-flank pair stiffness (N/m), > 0.
    interference_m : array_like
        ``c* - c`` (m).
    k_back_N_per_m : array_like, optional
        Back-flank pair stiffness (N/m); default ``k_EP``.

    Returns
    -------
    DoubleFlankContact

    Examples
    --------
    >>> r = double_flank_contact([1e3, 5e3], 4e8, 5e-6)
    >>> r.double_flank.tolist(), (r.tangent_stiffness_N_per_m / 4e8).tolist()
    ([True, False], [2.0, 1.0])
    """
    f = as_nonnegative("normal_load_N", normal_load_N)
    kd = as_positive("k_EP_N_per_m", k_EP_N_per_m)
    kb = kd if k_back_N_per_m is None else as_positive("k_back_N_per_m", k_back_N_per_m)
    i = as_closure(interference_m, "interference_m")
    f, kd, kb, i = np.broadcast_arrays(f, kd, kb, i)
    double = f < kd * i
    dd = np.where(double, (f + kb * i) / (kd + kb), f / kd)
    db = np.where(double, (kd * i - f) / (kd + kb), 0.0)
    return DoubleFlankContact(
        normal_load_N=f.copy(), interference_m=i.copy(), drive_deflection_m=dd,
        back_deflection_m=db, drive_load_N=kd * dd, back_load_N=kb * db, double_flank=double,
        tangent_stiffness_N_per_m=np.where(double, kd + kb, kd),
    )

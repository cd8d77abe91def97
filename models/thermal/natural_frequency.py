r"""Mesh natural frequency of a spur pair from the thermoelastic-backlash mesh stiffness.

Seed 000 compares the natural frequency read from vibration spectra with the mesh stiffness
(Table 6: "natural frequency, which correlates with stiffness"). The prediction here is the
torsional mesh mode of the two gear bodies on the mean mesh stiffness over a mesh cycle:

.. math::

    f_n = \frac{1}{2\pi} \sqrt{\frac{\bar k}{m_e}} .

The equivalent mass
-------------------
With the gear inertias ``J_1``, ``J_2`` and base radii ``r_b1``, ``r_b2``, the mesh spring acts
on the relative displacement along the line of action ``x = r_b1 theta_1 + r_b2 theta_2``
(rotations counted in the senses the mesh drives them). The mesh force ``k x`` gives the
torques ``-r_bi k x``:

.. math::

    J_1 \ddot\theta_1 = -r_{b1} k x, \quad J_2 \ddot\theta_2 = -r_{b2} k x
    \;\Rightarrow\;
    \ddot x = r_{b1}\ddot\theta_1 + r_{b2}\ddot\theta_2
            = -k x \left(\frac{r_{b1}^2}{J_1} + \frac{r_{b2}^2}{J_2}\right),

so the pair is one mass on the mesh spring,

.. math:: m_e = \left(\frac{r_{b1}^2}{J_1} + \frac{r_{b2}^2}{J_2}\right)^{-1}
              = \frac{J_1 J_2}{J_1 r_{b2}^2 + J_2 r_{b1}^2} ,

and ``omega^2 = k / m_e``. Shafts, couplings and the rest of the rig are left out: this is the
mode in which the two gear bodies swing against each other on the mesh (on an FZG rig the
slender shafts decouple them from the rest of the loop at the frequencies of interest).

The inertias, unless given, follow the package's one convention,
:mod:`models.geometry.inertia` (:data:`~models.geometry.inertia.EQUIVALENT_MASS_CONVENTION`):
bored discs of the face width whose outer radius is the operating pitch radius (default) or
the reference radius (``disc_radius="reference"``, 6.4 % lighter on FZG-C, 3 % in ``f_n``). A
real test gear's hub, web or shaft shoulder changes ``J`` more than that: give
``inertia_kg_m2`` when it is known.

The mean mesh stiffness
-----------------------
Every tooth pair runs along the whole path of contact A..E once while the mesh advances
``eps`` cycles, and the pairs in contact add, so the cycle mean of the mesh stiffness is

.. math:: \bar k = \frac{1}{p_b}\int_A^E k(s)\, ds ,

with ``k(s)`` the thermoelastic pair stiffness, Eq. (1) of
:mod:`models.thermal.thermoelastic`, at the load ``f_n(s) = f'_n R(s)``, ``f'_n = T / r_b1``
(exact; SEED-NOTES 5) and the seed's load share ``R``. The integral is taken by Gauss-Legendre
quadrature on each of the zones A-B, B-D, D-E (``R`` jumps at B and D; ``k`` is smooth inside
each zone), ``nodes_per_zone`` nodes each, 8 by default (agreement with a 201-point Simpson
rule per zone to better than 1e-9 for ``k_EP``, see the tests).

A caveat on which stiffness
---------------------------
Eq. (1) is a *secant* stiffness, load over the travel from the back-flank touch position
(thermoelastic module notes), and this is the stiffness seed 000 relates to the natural
frequency. A small vibration about the loaded state in single-flank contact sees the
*tangent* stiffness ``d f_n / d delta = k_EP``, which does not depend on backlash or closure.
The secant makes the predicted ``f_n`` very sensitive to backlash at low torque (FZG-C at
3.3 N m: 7.9 kHz at ``c = 0`` but 0.58 kHz at ``c = 40 um``, no closure), far more than the
seed's measured trends suggest. The seed's model is implemented as stated; a calibration
should be able to tell the two hypotheses apart (``c = 0``, ``Delta = 0`` gives the tangent
value at every load).

Speed for sampling
------------------
With ``q_j = k_EP,j / R_j``, ``a_j = w_j k_EP,j`` (``w_j`` the quadrature weights over
``p_b``) and, for a closure uniform along the path, ``u = c - (1 - chi) Delta``, Eq. (1) at
node ``j`` is

.. math::

    k_j = \frac{f'_n R_j k_{EP,j}}{f'_n R_j + u\, k_{EP,j}}
        = \frac{k_{EP,j}}{1 + (u / f'_n)\, q_j},
    \qquad \bar k = \sum_j \frac{a_j}{1 + (u / f'_n)\, q_j} ,

a function of the single number ``u / f'_n`` per run and parameter set.
:func:`prepare_natural_frequency` computes everything that does not depend on the sampled
parameters (geometry, nodes, ``R``, ``k_EP``, ``q``, ``a``, the inertias) once;
:func:`mesh_natural_frequency` then costs one outer product, one reciprocal and one
matrix-vector product over the nodes. The jammed test is one comparison: node ``j`` is jammed where
``1 + (u / f'_n) q_j <= 0``, so a run is jammed iff ``u / f'_n <= -1 / max_j q_j``.
``tests/benchmarks/bench_natural_frequency.py`` reports the rate.

Jammed runs
-----------
Where some node is jammed (thermal interference larger than the elastic deflection, module
notes of :mod:`models.thermal.thermoelastic`), Eq. (1) is undefined. ``jammed_model="nan"``
(default) returns NaN for ``f_n`` and ``k_mean`` there, with the bool mask ``jammed`` and the
smallest net deflection along the path ``min_net_deflection_m`` (``<= 0`` where jammed; a
continuous measure of the jam's depth for a penalty). ``jammed_model="double_flank"``
replaces Eq. (1) at the jammed nodes by the double-flank tangent stiffness ``2 k_EP`` (a
separate model of that state, not a continuation of Eq. 1). See the thermoelastic module for
how a likelihood should use these.

References
----------
.. [1] Seed 000 (FZG-C): load distribution R(theta), stiffness formula, Table 6 (natural
   frequency trends at 3.3, 35.3, 183.4 and 302 N m).
.. [2] ISO 6336-1:2019, clause 6.5 (resonance speed: the single-mass model of a gear pair,
   reduced mass ``m_red = m_1 m_2 / (m_1 + m_2)`` with ``m_i = J_i / r_bi^2``, the same
   ``m_e``).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Final, Literal

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError
from models.geometry.gear_pair import GearPair
from models.geometry.inertia import DiscRadius, equivalent_mass, gear_inertia
from models.stiffness.ishikawa import HertzOption, tooth_pair_stiffness
from models.stiffness.load_distribution import load_share_seed_000
from models.thermal.checks import as_backlash, as_chi, as_closure, as_positive
from models.thermal.thermoelastic import (
    JAMMED_STAND_IN,
    SEED_000_CHI,
    thermoelastic_pair_stiffness,
)

__all__ = [
    "JAMMED_MODELS",
    "JammedModel",
    "NaturalFrequency",
    "NaturalFrequencyModel",
    "mesh_natural_frequency",
    "mesh_natural_frequency_scalar",
    "prepare_natural_frequency",
]

JammedModel = Literal["nan", "double_flank"]
#: Accepted values of ``jammed_model``.
JAMMED_MODELS: Final[tuple[JammedModel, ...]] = ("nan", "double_flank")
# --- the prepared model ------------------------------------------------------------------
def _frozen(a: ArrayLike) -> np.ndarray:
    out = np.array(a, dtype=float)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class NaturalFrequencyModel:
    """What does not depend on the sampled parameters; made by :func:`prepare_natural_frequency`.

    Arrays are read-only. ``n`` is the number of quadrature nodes on the path.

    Attributes
    ----------
    pair : GearPair
    s_m : numpy.ndarray
        Quadrature nodes on the path of contact (m from T1), shape ``(n,)``.
    weights : numpy.ndarray
        Quadrature weights divided by the base pitch (1/1): ``k_mean = sum_j weights_j k_j``;
        they add up to the contact ratio.
    load_share : numpy.ndarray
        Seed 000's ``R`` at the nodes (-).
    k_EP_N_per_m : numpy.ndarray
        Elastic pair stiffness at the nodes (N/m): shape ``(n,)``, or ``(n_runs, n)`` for the
        load-dependent ``include_hertz="weber"``.
    torque_Nm : numpy.ndarray or None
        The runs' pinion torques (N m) the load-dependent ``k_EP`` was computed at; None when
        ``k_EP`` does not depend on the load.
    base_radius_pinion_m, base_radius_wheel_m : float
        ``r_b1``, ``r_b2`` (m).
    inertia_pinion_kg_m2, inertia_wheel_kg_m2 : float
        ``J_1``, ``J_2`` (kg m^2).
    equivalent_mass_kg : float
        ``m_e`` (kg).
    inertia_basis : str
        ``"operating"``, ``"reference"`` (discs) or ``"given"``.
    include_hertz : bool or str
        Contact term of Ishikawa's ``k_EP``.
    nodes_per_zone : int
    """

    pair: GearPair
    s_m: np.ndarray
    weights: np.ndarray
    load_share: np.ndarray
    k_EP_N_per_m: np.ndarray
    torque_Nm: np.ndarray | None
    base_radius_pinion_m: float
    base_radius_wheel_m: float
    inertia_pinion_kg_m2: float
    inertia_wheel_kg_m2: float
    equivalent_mass_kg: float
    inertia_basis: str
    include_hertz: HertzOption
    nodes_per_zone: int
    _q: np.ndarray = field(init=False, repr=False)
    _a: np.ndarray = field(init=False, repr=False)
    _q_max: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        q = _frozen(self.k_EP_N_per_m / self.load_share)
        object.__setattr__(self, "_q", q)
        object.__setattr__(self, "_a", _frozen(self.weights * self.k_EP_N_per_m))
        object.__setattr__(self, "_q_max", _frozen(q.max(axis=-1)))

    @property
    def n_nodes(self) -> int:
        """Number of quadrature nodes on the path."""
        return int(self.s_m.size)

    @property
    def k_EP_mean_N_per_m(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """Mean elastic mesh stiffness ``(1/p_b) int k_EP ds`` (N/m); per run if load dependent."""
        return np.asarray(self._a.sum(axis=-1))

    @property
    def elastic_natural_frequency_Hz(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """``f_n`` without backlash or thermal closure, ``sqrt(k_EP_mean / m_e) / (2 pi)`` (Hz)."""
        return np.sqrt(self.k_EP_mean_N_per_m / self.equivalent_mass_kg) / (2 * math.pi)


def _gauss_nodes(pair: GearPair, nodes_per_zone: int) -> tuple[np.ndarray, np.ndarray]:
    a, e, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    cuts = sorted({a, e - pb, a + pb, e}) if pair.contact_ratio < 2 else [a, e]
    x, w = np.polynomial.legendre.leggauss(nodes_per_zone)
    nodes, weights = [], []
    for lo, hi in itertools.pairwise(cuts):
        if hi - lo <= 1e-12 * pb:
            continue
        half = 0.5 * (hi - lo)
        nodes.append(lo + half * (x + 1.0))
        weights.append(half * w / pb)
    return np.concatenate(nodes), np.concatenate(weights)


def prepare_natural_frequency(
    pair: GearPair,
    *,
    include_hertz: HertzOption = False,
    shear_coefficient: float = 1.0,
    anchor: Literal["form", "base"] = "form",
    nodes_per_zone: int = 8,
    disc_radius: DiscRadius = "operating",
    inertia_kg_m2: tuple[float, float] | None = None,
    torque_Nm: ArrayLike | None = None,
) -> NaturalFrequencyModel:
    r"""Precompute the parameter-independent part of the natural-frequency prediction.

    Nodes and weights of the path quadrature (module notes), seed 000's ``R`` and Ishikawa's
    ``k_EP`` at the nodes, ``q = k_EP / R``, the inertias and ``m_e``.

    Parameters
    ----------
    pair : GearPair
        Contact ratio ``1 <= eps < 2`` (seed 000's ``R``).
    include_hertz : {False, "linear", "weber"}
        Contact term of ``k_EP`` (:func:`~models.stiffness.ishikawa_deflection`): none, as the
        seed (default); the constant Yang-Sun term; or Weber-Banaschek's load-dependent term,
        which needs the runs' ``torque_Nm`` and ties the model to them.
    shear_coefficient, anchor
        See :func:`~models.stiffness.ishikawa_deflection`.
    nodes_per_zone : int
        Gauss-Legendre nodes on each zone A-B, B-D, D-E (>= 1).
    disc_radius : {"operating", "reference"}
        Outer radius of the disc inertias (:func:`models.geometry.gear_inertia`); ignored when
        ``inertia_kg_m2`` is given.
    inertia_kg_m2 : (float, float), optional
        ``(J_1, J_2)`` (kg m^2), e.g. measured or from CAD.
    torque_Nm : array_like, optional
        The runs' pinion torques (N m), 1-D; required with ``include_hertz="weber"``, not
        allowed otherwise.

    Returns
    -------
    NaturalFrequencyModel

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> m = prepare_natural_frequency(load_gear_set("fzg-c").pair)
    >>> m.n_nodes, round(float(m.weights.sum()), 6) == round(m.pair.contact_ratio, 6)
    (24, True)
    """
    if (isinstance(nodes_per_zone, bool) or not isinstance(nodes_per_zone, int | np.integer)
            or nodes_per_zone < 1):
        raise ModelError(f"`nodes_per_zone` must be an integer >= 1, was {nodes_per_zone!r}")
    s, w = _gauss_nodes(pair, int(nodes_per_zone))
    share = load_share_seed_000(pair, s)
    t_runs: np.ndarray | None = None
    if include_hertz == "weber":
        if torque_Nm is None:
            raise ModelError("`torque_Nm` (the runs' torques) is required with "
                             "include_hertz='weber' (k_EP depends on the load), was None")
        t_runs = as_positive("torque_Nm", torque_Nm).astype(float)
        if t_runs.ndim != 1:
            raise ModelError(f"`torque_Nm` must be 1-D (one per run), had shape {t_runs.shape}")
        load = (t_runs / pair.base_radius(1))[:, None] * share
    elif torque_Nm is not None:
        raise ModelError(f"`torque_Nm` is only used with include_hertz='weber', was given with "
                         f"include_hertz={include_hertz!r}")
    else:
        load = np.ones_like(s)
    k_ep = tooth_pair_stiffness(pair, s, load_N=load, include_hertz=include_hertz,
                                shear_coefficient=shear_coefficient,
                                anchor=anchor).k_EP_N_per_m
    if inertia_kg_m2 is None:
        j1 = gear_inertia(pair, 1, disc_radius=disc_radius)
        j2 = gear_inertia(pair, 2, disc_radius=disc_radius)
        basis: str = disc_radius
    else:
        if len(inertia_kg_m2) != 2:
            raise ModelError(f"`inertia_kg_m2` must be a pair (J_1, J_2), was {inertia_kg_m2!r}")
        j1, j2 = (float(as_positive("inertia_kg_m2", v)) for v in inertia_kg_m2)
        basis = "given"
    rb1, rb2 = pair.base_radius(1), pair.base_radius(2)
    return NaturalFrequencyModel(
        pair=pair, s_m=_frozen(s), weights=_frozen(w), load_share=_frozen(share),
        k_EP_N_per_m=_frozen(k_ep), torque_Nm=None if t_runs is None else _frozen(t_runs),
        base_radius_pinion_m=rb1, base_radius_wheel_m=rb2, inertia_pinion_kg_m2=j1,
        inertia_wheel_kg_m2=j2, equivalent_mass_kg=equivalent_mass(j1, j2, rb1, rb2),
        inertia_basis=basis, include_hertz=include_hertz, nodes_per_zone=int(nodes_per_zone),
    )


# --- evaluation --------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class NaturalFrequency:
    """Predicted mesh natural frequencies, one per run and parameter set.

    All arrays have the broadcast shape of the arguments of :func:`mesh_natural_frequency`
    (e.g. ``(n_samples, n_runs)``).

    Attributes
    ----------
    f_n_Hz : numpy.ndarray
        ``sqrt(k_mean / m_e) / (2 pi)`` (Hz); NaN where ``jammed`` and
        ``jammed_model == "nan"``.
    k_mean_N_per_m : numpy.ndarray
        Mean mesh stiffness over the cycle (N/m), NaN likewise.
    jammed : numpy.ndarray
        Bool: Eq. (1) is undefined at some position on the path (thermal interference larger
        than the elastic deflection there).
    min_net_deflection_m : numpy.ndarray
        ``min_s (f_n(s) / k_EP(s) + c - c*(s))`` (m): ``<= 0`` exactly where jammed; its
        negative part measures the depth of the jam (for a penalty).
    jammed_model : str
        ``"nan"`` or ``"double_flank"``.
    """

    f_n_Hz: np.ndarray
    k_mean_N_per_m: np.ndarray
    jammed: np.ndarray
    min_net_deflection_m: np.ndarray
    jammed_model: JammedModel


def _check_torque(model: NaturalFrequencyModel, t: np.ndarray, shape: tuple[int, ...]) -> None:
    if model.torque_Nm is None:
        return
    n = model.torque_Nm.size
    if len(shape) == 0 or shape[-1] != n or not np.allclose(
            np.broadcast_to(t, shape), model.torque_Nm, rtol=1e-12, atol=0.0):
        raise ModelError(f"`torque_Nm` must be the {n} run torques the model was prepared at "
                         f"(load-dependent k_EP, include_hertz='weber') on the last axis, "
                         f"{model.torque_Nm.tolist()}")


def mesh_natural_frequency(
    model: NaturalFrequencyModel,
    torque_Nm: ArrayLike,
    thermal_closure_m: ArrayLike,
    backlash_m: ArrayLike,
    chi: ArrayLike = SEED_000_CHI,
    *,
    closure_along_path: bool = False,
    jammed_model: JammedModel = "nan",
) -> NaturalFrequency:
    r"""Mesh natural frequency for runs and parameter sets, vectorised (seed 000).

    .. math::

        f_n = \frac{1}{2\pi}\sqrt{\frac{\bar k}{m_e}}, \qquad
        \bar k = \sum_j w_j \frac{f'_n R_j k_{EP,j}}
                 {f'_n R_j - (1 - \chi) k_{EP,j} \Delta_j + c\, k_{EP,j}},
        \qquad f'_n = T / r_{b1} .

    The arguments broadcast against each other (numpy rules); for a campaign pass run
    conditions with shape ``(n_runs,)`` and parameters with shape ``(n_samples, 1)`` (or
    ``(n_samples, n_runs)`` for a per-run backlash, SEED-NOTES 11) to get
    ``(n_samples, n_runs)``.

    Parameters
    ----------
    model : NaturalFrequencyModel
        From :func:`prepare_natural_frequency`.
    torque_Nm : array_like
        Pinion torque of each run (N m), > 0.
    thermal_closure_m : array_like
        ``Delta_1 + Delta_2`` (m), the run's temperature state; uniform along the path, or
        with ``closure_along_path=True`` given at ``model.s_m`` on the last axis.
    backlash_m : array_like
        Total backlash ``c`` (m), >= 0.
    chi : array_like
        Correction factor (-), in [0, 1].
    closure_along_path : bool
        See ``thermal_closure_m``.
    jammed_model : {"nan", "double_flank"}
        What to return where Eq. (1) is undefined (module notes).

    Returns
    -------
    NaturalFrequency

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> m = prepare_natural_frequency(load_gear_set("fzg-c").pair)
    >>> r = mesh_natural_frequency(m, [183.4, 302.0], 10.2934e-6, [[2e-6], [40e-6]])
    >>> r.f_n_Hz.shape, bool(r.f_n_Hz[0, 1] < r.f_n_Hz[0, 0]), bool(r.f_n_Hz[1, 1] > r.f_n_Hz[1, 0])
    ((2, 2), True, True)
    """
    if jammed_model not in JAMMED_MODELS:
        raise ModelError(f"`jammed_model` must be one of {JAMMED_MODELS}, was {jammed_model!r}")
    t = as_positive("torque_Nm", torque_Nm)
    d = as_closure(thermal_closure_m)
    c = as_backlash(backlash_m)
    x = as_chi(chi)
    big_f = t / model.base_radius_pinion_m
    q, a = model._q, model._a
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if not closure_along_path:
            u = c - (1.0 - x) * d
            ratio = u / big_f                              # shape P
            _check_torque(model, t, ratio.shape)
            jammed = ratio * model._q_max <= -1.0
            min_net = big_f / model._q_max + u
            den = ratio[..., None] * q                     # P + (n,)
            den += 1.0
        else:
            if d.ndim == 0 or d.shape[-1] != model.n_nodes:
                raise ModelError(f"`thermal_closure_m` must have the {model.n_nodes} nodes of "
                                 f"`model.s_m` on its last axis with closure_along_path=True, "
                                 f"had shape {d.shape}")
            u_j = c[..., None] - (1.0 - x[..., None]) * d  # P + (n,)
            bf = big_f[..., None]
            _check_torque(model, t, np.broadcast_shapes(u_j.shape[:-1], big_f.shape))
            den = 1.0 + u_j * q / bf
            jammed = np.any(den <= 0.0, axis=-1)
            min_net = np.min(bf / q + u_j, axis=-1)
        if jammed_model == "double_flank" and np.any(jammed):
            k_nodes = np.where(den > 0.0, a / den, 2.0 * a)
            k_mean = k_nodes.sum(axis=-1)
        else:
            np.reciprocal(den, out=den)
            k_mean = den @ a if a.ndim == 1 else (den * a).sum(axis=-1)
            if np.any(jammed):
                k_mean = np.where(jammed, JAMMED_STAND_IN, k_mean)
    k_mean = np.asarray(k_mean, dtype=float)
    f_n = np.sqrt(k_mean / model.equivalent_mass_kg) * (1.0 / (2.0 * math.pi))
    shape = np.broadcast_shapes(k_mean.shape, jammed.shape, min_net.shape)

    def full(a: np.ndarray) -> np.ndarray:
        return a if a.shape == shape else np.broadcast_to(a, shape)

    return NaturalFrequency(
        f_n_Hz=full(f_n), k_mean_N_per_m=full(k_mean), jammed=full(jammed),
        min_net_deflection_m=full(min_net), jammed_model=jammed_model,
    )


def mesh_natural_frequency_scalar(
    model: NaturalFrequencyModel,
    torque_Nm: float,
    thermal_closure_m: float,
    backlash_m: float,
    chi: float = SEED_000_CHI,
    *,
    run: int = 0,
) -> float:
    """One natural frequency by a plain Python loop over the nodes (Hz); the slow reference.

    Calls :func:`~models.thermal.thermoelastic.thermoelastic_pair_stiffness` (the scalar API)
    at each node, sums ``w_j k_j`` and takes ``sqrt(k_mean / m_e) / (2 pi)``. Used by the
    tests and the benchmark as an independent implementation of :func:`mesh_natural_frequency`.

    Parameters
    ----------
    model : NaturalFrequencyModel
    torque_Nm : float
        Pinion torque (N m).
    thermal_closure_m : float
        ``Delta_1 + Delta_2`` (m), uniform along the path.
    backlash_m : float
        Total backlash (m).
    chi : float
        Correction factor (-).
    run : int
        Row of a load-dependent ``k_EP`` (``include_hertz="weber"``).

    Returns
    -------
    float
        ``f_n`` (Hz).

    Raises
    ------
    ThermalJamError
        At the first jammed node.
    """
    k_ep = model.k_EP_N_per_m if model.k_EP_N_per_m.ndim == 1 else model.k_EP_N_per_m[run]
    big_f = float(torque_Nm) / model.base_radius_pinion_m
    total = 0.0
    for w_j, r_j, k_j in zip(model.weights.tolist(), model.load_share.tolist(), k_ep.tolist(),
                             strict=True):
        total += w_j * thermoelastic_pair_stiffness(big_f * r_j, k_j, thermal_closure_m,
                                                    backlash_m, chi)
    return math.sqrt(total / model.equivalent_mass_kg) / (2.0 * math.pi)

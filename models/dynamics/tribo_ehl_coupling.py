r"""Seed 002's iterative decoupling of the six-DOF dynamics and the mixed-EHL contact model.

The loop (seed 002, "iterative decoupling method" and its flowchart):

0. initial film stiffness and friction: the mixed-EHL state of every tooth pair at the
   quasi-static load share ``N_i = W_0 k_mi / sum_j k_mj`` (the "steady-state" lubrication the
   seed compares against), kept as :attr:`TriboSolution.steady_contact`;
1. dynamics (:mod:`models.dynamics.tribo`) with the current per-pair film stiffness ``k_hi``
   (in series with the mesh stiffness) and signed friction ``mu_i``, run to the periodic
   steady state; one period of dynamic tooth-pair loads ``N_i(t)``;
2. EHL at every step and loaded pair (:func:`contact_cycle`): Moes central film with the
   thermal factor ``C_t`` and the Greenwood-Tripp load split (:func:`models.ehl.mixed_contact`,
   Doolittle-Tait / Carreau lubricant), film parameter ``Lambda``, signed mixed friction
   coefficient, and the film stiffness ``k_h = -dF/dh_c`` of the *mixed* contact by a central
   difference in ``ln F`` (``F (1 +- epsilon)``, ``epsilon = 1e-2``;
   :func:`models.ehl.asperity.mixed_film_stiffness`);
3. convergence: the largest relative change of ``k_h`` over the loaded points (seed 002's
   criterion ``|k_h^new - k_h^old| / k_h^old < 1e-3``) and of the friction coefficient
   (``max |f^new - f^old| / max |f^old|``, the other quantity the seed initialises and feeds
   back) must both be below the tolerance; otherwise the new tables go back to step 1.

The kinematics of the contact (radii, rolling and sliding velocities) are those of the nominal
speed at the pair's position (:meth:`~models.geometry.GearPair.surface_velocities`); the
vibration velocities are neglected against them. The EHL is evaluated at ``ehl_samples``
(default 128) equally spaced instants of the mesh period; the tables at the RK4 half steps are
interpolated linearly in time between them (film *compliance* ``1/k_h`` and friction), and
next to a sample where the pair is unloaded the loaded neighbour's value is held.
The flash-temperature energy equation of seed 002 is not solved: the film is evaluated at the
inlet temperature with Moes' isothermal film times ``C_t``, and the shear stress at the inlet
temperature. With seed 002's lubricant the film friction then sits at the assumed limiting
shear stress ``Lambda_L p`` over most of the path (:mod:`models.ehl.asperity`): its level is
that of the assumption ``limiting_shear_coeff = 0.07``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from models.dynamics.tribo import TriboDynamics
from models.dynamics.tribo_integrate import TriboRecord, tribo_settle
from models.ehl.asperity import SEED_002_ROUGHNESS, Roughness, mixed_film_stiffness
from models.ehl.lubricant import SEED_002_LUBRICANT, Lubricant
from models.errors import ModelError
from models.geometry.gear_pair import GearPair

__all__ = [
    "ContactCycle",
    "Lubrication",
    "TriboSolution",
    "contact_cycle",
    "lubrication_tables",
    "quasi_static_loads",
    "relative_change",
    "solve_tribo_dynamics",
    "tribo_iteration",
]


@dataclass(frozen=True)
class Lubrication:
    """Inputs of the mixed-EHL contact model (SI units).

    Attributes
    ----------
    lubricant : Lubricant
        Doolittle-Tait / Carreau lubricant; default seed 002's table.
    roughness : Roughness
        Flank roughness; default seed 002's (0.4 um RMS each, 6 um summit radius).
    inlet_temperature_K : float or None
        Oil inlet temperature (K); None: the lubricant's reference temperature (seed 002 is
        silent; its table's ``T_r = 348.15 K``).
    asperity_friction : float
        Boundary friction coefficient ``f_a`` (-), not in seed 002; 0.1 assumed.
    limiting_shear_coeff : float
        Limiting shear stress over pressure (-), 0.07 assumed.
    thermal : bool
        Apply Moes' film the thermal factor ``C_t``.
    film_load_step : float
        Relative load step of the central difference giving ``k_h`` (-).
    """

    lubricant: Lubricant = SEED_002_LUBRICANT
    roughness: Roughness = SEED_002_ROUGHNESS
    inlet_temperature_K: float | None = None
    asperity_friction: float = 0.1
    limiting_shear_coeff: float = 0.07
    thermal: bool = True
    film_load_step: float = 1e-2


@dataclass(frozen=True)
class ContactCycle:
    """Mixed-EHL state of every tooth-pair slot at the EHL samples of a mesh period.

    Arrays are ``(n_samples, n_slots)``; NaN where the slot carries no load (off the path of
    contact, or separated when no load floor is used).

    Attributes
    ----------
    positions_m : numpy.ndarray
        Slot positions on the line of action from T1 (m).
    load_N : numpy.ndarray
        Dynamic tooth-pair load (N); the EHL state is that of ``max(load, load floor)``, so
        where ``load_N <= 0`` (a separated pair) it describes the floor load.
    film_thickness_m : numpy.ndarray
        Central film thickness with ``C_t`` and load sharing (m).
    film_parameter : numpy.ndarray
        ``Lambda = h_c / sqrt(sigma_1^2 + sigma_2^2)`` (-).
    friction : numpy.ndarray
        Signed friction coefficient ``lambda f`` (-): negative before, positive after the
        pitch point.
    film_stiffness_N_m : numpy.ndarray
        ``k_h = -dF/dh_c`` of the mixed contact (N/m).
    asperity_share : numpy.ndarray
        ``1 / gamma_2``, share of the load on the asperities (-).
    thermal_factor : numpy.ndarray
        ``C_t`` (-).
    """

    positions_m: np.ndarray
    load_N: np.ndarray
    film_thickness_m: np.ndarray
    film_parameter: np.ndarray
    friction: np.ndarray
    film_stiffness_N_m: np.ndarray
    asperity_share: np.ndarray
    thermal_factor: np.ndarray

    @property
    def loaded(self) -> np.ndarray:
        """Slots that carry load (bool, ``(N, n_slots)``)."""
        return np.isfinite(self.film_stiffness_N_m)

    def along_path(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """One tooth pair's passage: ``(positions, values)`` of field ``name``, loaded points only.

        The slots are stitched incoming first (the :meth:`MeshCycle.tooth_pair_history`
        order), so positions increase along the path of contact.
        """
        order = slice(None, None, -1)
        s = self.positions_m[:, order].T.ravel()
        v = np.asarray(getattr(self, name))[:, order].T.ravel()
        keep = self.loaded[:, order].T.ravel()
        return s[keep], v[keep]


def _stride(model: TriboDynamics, n_samples: int) -> int:
    n = model.steps_per_period
    if int(n_samples) != n_samples or n_samples < 4 or n % int(n_samples):
        raise ModelError(
            f"`ehl_samples` ({n_samples!r}) must be an integer >= 4 dividing the "
            f"{n} steps per mesh period"
        )
    return n // int(n_samples)


def quasi_static_loads(model: TriboDynamics, ehl_samples: int = 128) -> np.ndarray:
    """Static load share ``N_i = W_0 k_mi / sum_j k_mj`` (N) at the EHL samples, ``(n, slots)``."""
    km = np.asarray(model.mesh_stiffness_N_m)[:: 2 * _stride(model, ehl_samples)]
    return model.load_N * km / km.sum(axis=1, keepdims=True)


def contact_cycle(
    pair: GearPair,
    model: TriboDynamics,
    pair_load_N: np.ndarray,
    pinion_speed_rpm: float,
    lubrication: Lubrication = Lubrication(),
    ehl_samples: int = 128,
    load_floor_N: float = 0.0,
) -> ContactCycle:
    """Mixed-EHL state at ``ehl_samples`` equally spaced step starts (step 2 of the loop).

    Parameters
    ----------
    pair : GearPair
        Geometry and material (``E' = E / (1 - nu^2)``, both gears of one material).
    model : TriboDynamics
        Supplies the slot positions and which slots are on the path of contact.
    pair_load_N : numpy.ndarray
        ``(ehl_samples, n_slots)`` loads (N) at every ``N / ehl_samples``-th step start, e.g.
        ``record.pair_load_N[::stride]``.
    pinion_speed_rpm : float
    lubrication : Lubrication
    ehl_samples : int
        Samples per mesh period; must divide the model's steps per period.
    load_floor_N : float
        The EHL of a pair on the path of contact is evaluated at ``max(N_i, load_floor_N)``
        (N). 0: pairs with ``N_i <= 1e-9 W_0`` are left out (NaN). See
        :func:`solve_tribo_dynamics`.
    """
    stride = _stride(model, ehl_samples)
    s = np.asarray(model.positions_m)[:: 2 * stride]
    loads = np.asarray(pair_load_N, float)
    if loads.shape != s.shape:
        raise ModelError(f"`pair_load_N` must have shape {s.shape}, got {loads.shape}")
    floor = float(load_floor_N)
    loads_eval = np.maximum(loads, floor)
    # loads below 1e-9 W_0 count as separated: the film there is unbounded (h ~ 1/F)
    touching = loads_eval > 1e-9 * model.load_N
    loaded = (np.asarray(model.mesh_stiffness_N_m)[:: 2 * stride] > 0) & touching
    out = {k: np.full(s.shape, np.nan) for k in ("h", "lam", "f", "kh", "share", "ct")}
    if np.any(loaded):
        sl = s[loaded]
        F = loads_eval[loaded]
        r1, r2 = pair.curvature_radii(sl)
        R = r1 * r2 / (r1 + r2)
        u1, u2 = pair.surface_velocities(sl, pinion_speed_rpm)
        mat = pair.pinion.material
        E = mat.youngs_modulus_Pa / (1 - mat.poisson_ratio**2)
        mc, kh = mixed_film_stiffness(
            F,
            pair.face_width_m,
            R,
            u1,
            u2,
            E,
            rel_step=lubrication.film_load_step,
            lubricant=lubrication.lubricant,
            roughness=lubrication.roughness,
            inlet_temperature_K=lubrication.inlet_temperature_K,
            asperity_friction=lubrication.asperity_friction,
            limiting_shear_coeff=lubrication.limiting_shear_coeff,
            thermal=lubrication.thermal,
        )
        out["h"][loaded] = mc.h_c_m
        out["lam"][loaded] = mc.film_parameter
        out["f"][loaded] = mc.friction
        # k_h ~ F^2 underflows to 0 at vanishing loads without a floor: keep it > 0
        out["kh"][loaded] = np.maximum(kh, np.finfo(float).tiny)
        out["share"][loaded] = 1.0 / mc.gamma_2
        out["ct"][loaded] = mc.C_t
    return ContactCycle(
        s,
        np.where(loaded, loads, np.nan),
        out["h"],
        out["lam"],
        out["f"],
        out["kh"],
        out["share"],
        out["ct"],
    )


def _resample(values: np.ndarray, n_rows: int, fill: float) -> np.ndarray:
    """Periodic samples (n, ns), NaN where unloaded -> ``n_rows`` rows, linear in time.

    Between a loaded and an unloaded sample the loaded value is held; ``fill`` where neither
    is loaded. Past the last sample the next period's first sample is used with the slots
    shifted by one: after one mesh period slot ``k`` is where slot ``k - 1`` was at phase 0
    (``A + (tau + m) p_b``, ``m`` decreasing with ``k``); the most advanced slot has left the
    path.
    """
    v = np.asarray(values, float)
    n = v.shape[0]
    nxt = np.vstack([v[1:], np.concatenate([[np.nan], v[0, :-1]])[None, :]])
    x = np.arange(n_rows) * (n / n_rows)
    i0 = np.floor(x).astype(int) % n
    w = (x - np.floor(x))[:, None]
    a, b = v[i0], nxt[i0]
    fa, fb = np.isfinite(a), np.isfinite(b)
    with np.errstate(invalid="ignore"):
        both = (1 - w) * a + w * b
    return np.where(fa & fb, both, np.where(fa, a, np.where(fb, b, fill)))


def lubrication_tables(contact: ContactCycle, n_rows: int) -> tuple[np.ndarray, np.ndarray]:
    """Film stiffness (N/m; ``inf`` where unloaded) and signed friction at ``n_rows`` half steps.

    The film *compliance* ``1/k_h`` and the friction are interpolated linearly in time.
    """
    compliance = _resample(1.0 / contact.film_stiffness_N_m, n_rows, 0.0)
    with np.errstate(divide="ignore"):
        kh = np.where(compliance > 0, 1.0 / compliance, np.inf)
    return kh, _resample(contact.friction, n_rows, 0.0)


def relative_change(
    old: ContactCycle, new: ContactCycle, load_scale_N: float = 0.0
) -> tuple[float, float]:
    """``(max |dk_h| / k_h, max |df| / max |f|)`` between two contact cycles (-).

    Compared where both are loaded. A sample loaded in one cycle only counts as a relative
    change of 1 unless its load is below ``load_scale_N`` (a pair just touching or just
    separating, whose film state is immaterial to the dynamics).
    """
    flip = old.loaded != new.loaded
    if np.any(flip):
        lo = np.where(np.isfinite(old.load_N), old.load_N, 0.0)
        ln = np.where(np.isfinite(new.load_N), new.load_N, 0.0)
        if np.any(flip & (np.maximum(lo, ln) > load_scale_N)):
            return 1.0, 1.0
    m = old.loaded & new.loaded
    if not np.any(m):
        return 0.0, 0.0
    dk = float(
        np.max(
            np.abs(new.film_stiffness_N_m[m] - old.film_stiffness_N_m[m])
            / old.film_stiffness_N_m[m]
        )
    )
    fmax = float(np.max(np.abs(old.friction[m])))
    df = float(np.max(np.abs(new.friction[m] - old.friction[m])))
    return dk, (df / fmax if fmax > 0 else df)


def tribo_iteration(
    pair: GearPair,
    model: TriboDynamics,
    contact: ContactCycle,
    pinion_speed_rpm: float,
    lubrication: Lubrication = Lubrication(),
    y0: np.ndarray | None = None,
    settle_tol: float = 1e-7,
    ehl_samples: int = 128,
    load_floor_N: float = 0.0,
) -> tuple[TriboDynamics, np.ndarray, TriboRecord, ContactCycle]:
    """One pass of the loop: tables from ``contact`` -> periodic dynamics -> new contact cycle.

    Parameters
    ----------
    pair, pinion_speed_rpm, lubrication
        As in :func:`solve_tribo_dynamics`.
    model : TriboDynamics
        The dynamics; its film-stiffness and friction tables are replaced.
    contact : ContactCycle
        The current iterate (film stiffness and friction at the EHL samples).
    y0 : numpy.ndarray, optional
        Start state of the dynamics (e.g. the previous periodic state).
    settle_tol : float
        Periodicity tolerance of :func:`~models.dynamics.tribo_integrate.tribo_settle`.
    ehl_samples : int
        EHL samples per mesh period.
    load_floor_N : float
        EHL load floor (N), see :func:`contact_cycle`.

    Returns
    -------
    tuple
        The model with the tables used, the periodic state at phase 0, the recorded period
        and the new :class:`ContactCycle`.
    """
    stride = _stride(model, ehl_samples)
    kh, mu = lubrication_tables(contact, 2 * model.steps_per_period)
    m = model.with_lubrication(kh, mu)
    y, _, rec = tribo_settle(m, y0, tol=settle_tol)
    new = contact_cycle(
        pair, m, rec.pair_load_N[::stride], pinion_speed_rpm, lubrication, ehl_samples, load_floor_N
    )
    return m, y, rec, new


def _relax(old: ContactCycle, new: ContactCycle, omega: float) -> ContactCycle:
    """``(1 - omega) old + omega new`` for the film compliance and the friction."""
    c = (1 - omega) / old.film_stiffness_N_m + omega / new.film_stiffness_N_m
    f = (1 - omega) * old.friction + omega * new.friction
    return replace(new, film_stiffness_N_m=1.0 / c, friction=f)


@dataclass(frozen=True)
class TriboSolution:
    """Converged state of the decoupling loop (SI units; ``N`` steps per mesh period).

    Attributes
    ----------
    model : TriboDynamics
        The model with the film-stiffness and friction tables of the last dynamics run.
    record : TriboRecord
        The periodic response of that run: DTE, dynamic mesh force, pair loads, state.
    contact : ContactCycle
        The EHL state along the cycle from that run's loads (film thickness, Lambda, signed
        friction coefficient, film stiffness, asperity share), ``(N, n_slots)``.
    steady_contact : ContactCycle
        Iteration 0: the EHL state at the quasi-static load share (the uncoupled reference).
    state : numpy.ndarray
        Periodic state at phase 0 (10,).
    iterations : int
        Dynamics runs made.
    history : numpy.ndarray
        ``(iterations, 2)``: relative changes of ``k_h`` and of ``f`` after each run.
    tolerance : float
    relaxation : float
        Under-relaxation used (1: plain substitution).
    """

    model: TriboDynamics
    record: TriboRecord
    contact: ContactCycle
    steady_contact: ContactCycle
    state: np.ndarray
    iterations: int
    history: np.ndarray
    tolerance: float
    relaxation: float = 1.0

    @property
    def contraction(self) -> float:
        """Ratio of the last two changes ``rho`` (-): how fast the loop was converging.

        NaN after a single iteration.
        """
        if self.iterations < 2:
            return math.nan
        last, prev = (float(np.max(r)) for r in self.history[-1:-3:-1])
        return last / prev if prev > 0 else math.nan

    @property
    def distance_estimate(self) -> float:
        """Rough relative distance from the exact fixed point, ``Delta rho / (1 - rho)`` (-).

        The seed's test bounds the change of the last iteration, not the distance from the
        fixed point; for plain substitution converging linearly with contraction ``rho`` the
        remaining error is about ``Delta rho / (1 - rho)``, more than ``Delta`` when
        ``rho > 1/2``. Two changes give a noisy ``rho``: treat this as an order of magnitude
        (at 2000 rpm the true distance, from a run to 1e-6, is 1.6x the estimate). NaN when
        ``rho`` is unknown or ``>= 1``, or with under-relaxation.
        """
        rho = self.contraction
        if self.relaxation != 1 or not (0 <= rho < 1):
            return math.nan
        return float(np.max(self.history[-1])) * rho / (1 - rho)

    @property
    def phase(self) -> np.ndarray:
        """Mesh-cycle phase of the samples (-)."""
        n = self.record.time_s.size
        return np.arange(n) / n

    @property
    def dte_m(self) -> np.ndarray:
        """Dynamic transmission error (m)."""
        return self.record.dte_m

    @property
    def mesh_force_N(self) -> np.ndarray:  # noqa: N802 (unit in the name)
        """Dynamic mesh force (N)."""
        return self.record.mesh_force_N


def solve_tribo_dynamics(
    pair: GearPair,
    model: TriboDynamics,
    pinion_speed_rpm: float,
    lubrication: Lubrication = Lubrication(),
    *,
    tol: float = 1e-3,
    max_iterations: int = 30,
    settle_tol: float = 1e-7,
    ehl_samples: int = 128,
    load_scale: float = 1e-3,
    load_floor: float = 0.05,
    relaxation: float = 1.0,
) -> TriboSolution:
    """Iterate dynamics and mixed EHL to a consistent state (seed 002's decoupling loop).

    Parameters
    ----------
    pair : GearPair
        The pair ``model`` was built from (:func:`~models.dynamics.tribo.build_tribo_dynamics`).
    model : TriboDynamics
        Dynamics; its film-stiffness and friction tables are replaced by the loop.
    pinion_speed_rpm : float
        Speed the model was built for (rolling and sliding velocities of the EHL).
    lubrication : Lubrication
    tol : float
        Convergence tolerance on the relative changes (seed 002: 1e-3).
    max_iterations : int
        Cap on dynamics runs.
    settle_tol : float
        Periodicity tolerance of each dynamics run (:func:`tribo_settle`); keep it well
        below ``tol``.
    ehl_samples : int
        EHL evaluations per mesh period (must divide the steps per period); the tables at the
        RK4 half steps are interpolated linearly between them.
    load_scale : float
        Loads below ``load_scale W_0`` may switch between loaded and unloaded between
        iterations without preventing convergence (:func:`relative_change`).
    load_floor : float
        EHL loads are floored at ``load_floor W_0`` (:func:`contact_cycle`). The film
        stiffness of a line contact vanishes like ``F^2`` as the load goes to zero (the film
        grows like ``1/F``), so without a floor a pair that separates in one iteration gets a
        near-zero stiffness in the next and the loop cannot settle; 0.05 (86 N for seed 002)
        keeps ``k_h`` at a few 1e6 N/m there. It changes nothing where no pair is that light.
    relaxation : float
        Under-relaxation ``omega`` in (0, 1]: the next iterate is ``(1 - omega)`` old plus
        ``omega`` new (film compliance and friction). 1 is seed 002's plain substitution;
        the convergence test is always on the un-relaxed change ``G(x) - x``.

    Raises
    ------
    ModelError
        No convergence within ``max_iterations`` (the message gives the last changes), or a
        dynamics run that does not become periodic.
    """
    if not (math.isfinite(tol) and tol > 0) or int(max_iterations) < 1:
        raise ModelError("need tol > 0 and max_iterations >= 1")
    if not 0 < relaxation <= 1:
        raise ModelError(f"`relaxation` must be in (0, 1], was {relaxation!r}")
    floor = load_floor * model.load_N
    steady = contact_cycle(
        pair,
        model,
        quasi_static_loads(model, ehl_samples),
        pinion_speed_rpm,
        lubrication,
        ehl_samples,
        floor,
    )
    contact = steady
    y: np.ndarray | None = None
    history = []
    for it in range(1, int(max_iterations) + 1):
        m, y, rec, new = tribo_iteration(
            pair, model, contact, pinion_speed_rpm, lubrication, y, settle_tol, ehl_samples, floor
        )
        dk, df = relative_change(contact, new, load_scale * model.load_N)
        history.append((dk, df))
        if max(dk, df) < tol:
            return TriboSolution(
                m, rec, new, steady, y, it, np.array(history), tol, float(relaxation)
            )
        contact = new if relaxation == 1 else _relax(contact, new, relaxation)
    dk, df = history[-1]
    raise ModelError(
        f"tribo-dynamic loop did not converge in {max_iterations} iterations: "
        f"last relative change of film stiffness {dk:.3g}, of friction "
        f"{df:.3g} (tolerance {tol:g}); with loss of contact try relaxation < 1"
    )

"""Tribo-dynamic cases as data files: seed 002's parameter tables (``cases/*.toml``) and loader.

A case names a gear set (:func:`models.geometry.load_gear_set`) and gives the operating point,
masses and inertias, mesh damping and backlash, bearings, lubricant (Doolittle-Tait /
Carreau), roughness, friction constants and solver settings; units are in the key names.
:func:`load_tribo_case` checks every key (an unknown or missing key raises
:class:`~models.errors.ModelError` naming it and the file) and returns a :class:`TriboCase`,
whose :meth:`TriboCase.dynamics` builds the six-DOF model
(:func:`~models.dynamics.tribo.build_tribo_dynamics`) and :func:`solve_tribo_case` runs the
decoupling loop (:func:`~models.dynamics.tribo_ehl_coupling.solve_tribo_dynamics`).

Shipped cases (their comments say which table each number comes from and what was assumed
where the seed is silent):

* ``seed-002-tribo``: seed 002's tables, with ``beta_K = 6.0e-3 /K`` (printed 6.0e-4, an
  extraction error: see :mod:`models.ehl.lubricant`) and the printed reference viscosity
  ``mu_R = 1.42 Pa s``, marked SUSPECT in the file: at it the pair runs in full film and the
  seed's qualitative statements do not hold;
* ``seed-002-tribo-mixed``: the same with ``mu_R = 0.142 Pa s``, whose converged state
  reproduces seed 002's statements (mixed regime ``1 < Lambda < 3``, film stiffness about two
  orders of magnitude above the mesh stiffness, minimal change of the comprehensive
  stiffness). Use this one to reproduce the seed's behaviour.

Values are range-checked on loading (positive masses, inertias, viscosity, roughness, ...;
``0 < R0 < 1``, ``0 < n <= 1``, ``relaxation`` in (0, 1]): a value outside raises
:class:`~models.errors.ModelError` naming ``section.key``.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from models.dynamics.tribo import TriboDynamics, build_tribo_dynamics
from models.dynamics.tribo_ehl_coupling import Lubrication, TriboSolution, solve_tribo_dynamics
from models.ehl.asperity import Roughness
from models.ehl.lubricant import Lubricant
from models.errors import GeometryError, ModelError
from models.geometry.gear_pair import GearPair
from models.geometry.gear_sets import load_gear_set

__all__ = [
    "TriboCase",
    "load_tribo_case",
    "shipped_tribo_cases",
    "solve_tribo_case",
    "tribo_case_path",
]

_DIR = Path(__file__).resolve().parent / "cases"

# section -> key -> (attribute, factor to SI, required)
_SCHEMA: dict[str, dict[str, tuple[str, float, bool]]] = {
    "operating": {
        "pinion_speed_rpm": ("pinion_speed_rpm", 1.0, True),
        "torque_Nm": ("torque_Nm", 1.0, True),
        "inlet_temperature_K": ("inlet_temperature_K", 1.0, False),
    },
    "inertia": {
        "pinion_mass_kg": ("mass_p_kg", 1.0, True),
        "wheel_mass_kg": ("mass_g_kg", 1.0, True),
        "pinion_inertia_kgm2": ("inertia_p_kgm2", 1.0, True),
        "wheel_inertia_kgm2": ("inertia_g_kgm2", 1.0, True),
    },
    "mesh": {
        "damping_ratio": ("mesh_damping_ratio", 1.0, True),
        "backlash_um": ("backlash_m", 1e-6, True),
    },
    "bearings": {
        "stiffness_x_N_m": ("bearing_stiffness_x_N_m", 1.0, True),
        "stiffness_y_N_m": ("bearing_stiffness_y_N_m", 1.0, True),
        "damping_ratio": ("bearing_damping_ratio", 1.0, True),
    },
    "lubricant": {
        "mu_ref_Pas": ("mu_ref_Pas", 1.0, True),
        "T_ref_K": ("T_ref_K", 1.0, True),
        "B0": ("B0", 1.0, True),
        "R0": ("R0", 1.0, True),
        "epsilon_per_K": ("epsilon_per_K", 1.0, True),
        "K0_prime": ("K0_prime", 1.0, True),
        "K00_GPa": ("K00_Pa", 1e9, True),
        "beta_K_per_K": ("beta_K_per_K", 1.0, True),
        "a_V_per_K": ("a_V_per_K", 1.0, True),
        "n_power": ("n_power", 1.0, True),
        "G_cr_kPa": ("G_cr_Pa", 1e3, True),
        "alpha_per_GPa": ("alpha_per_Pa", 1e-9, True),
        "conductivity_W_mK": ("conductivity_W_mK", 1.0, True),
        "density_kg_m3": ("density_kg_m3", 1.0, True),
        "specific_heat_J_kgK": ("specific_heat_J_kgK", 1.0, True),
    },
    "roughness": {
        "sigma_pinion_um": ("sigma_1_m", 1e-6, True),
        "sigma_wheel_um": ("sigma_2_m", 1e-6, True),
        "asperity_radius_um": ("asperity_radius_m", 1e-6, True),
        "eta_beta_sigma": ("eta_beta_sigma", 1.0, True),
        "d_d_um": ("d_d_m", 1e-6, False),
    },
    "friction": {
        "asperity_friction": ("asperity_friction", 1.0, True),
        "limiting_shear_coeff": ("limiting_shear_coeff", 1.0, True),
    },
    "solver": {
        "tolerance": ("tol", 1.0, False),
        "max_iterations": ("max_iterations", 1.0, False),
        "ehl_samples": ("ehl_samples", 1.0, False),
        "steps_per_period": ("steps_per_period", 1.0, False),
        "load_floor": ("load_floor", 1.0, False),
        "relaxation": ("relaxation", 1.0, False),
        "thermal": ("thermal", 1.0, False),
    },
}
_CASE = {"name", "source", "gear_set"}

# (section, key) -> (lower, upper, lower included, upper included), in the file's units;
# None: unbounded. Keys not listed (epsilon_per_K, beta_K_per_K, a_V_per_K, d_d_um) take any
# finite value. A value outside raises ModelError naming section.key.
_RANGES: dict[tuple[str, str], tuple[float | None, float | None, bool, bool]] = {
    ("operating", "pinion_speed_rpm"): (0.0, None, False, False),
    ("operating", "torque_Nm"): (0.0, None, False, False),
    ("operating", "inlet_temperature_K"): (0.0, None, False, False),
    ("inertia", "pinion_mass_kg"): (0.0, None, False, False),
    ("inertia", "wheel_mass_kg"): (0.0, None, False, False),
    ("inertia", "pinion_inertia_kgm2"): (0.0, None, False, False),
    ("inertia", "wheel_inertia_kgm2"): (0.0, None, False, False),
    ("mesh", "damping_ratio"): (0.0, None, True, False),
    ("mesh", "backlash_um"): (0.0, None, True, False),
    ("bearings", "stiffness_x_N_m"): (0.0, None, False, False),
    ("bearings", "stiffness_y_N_m"): (0.0, None, False, False),
    ("bearings", "damping_ratio"): (0.0, None, True, False),
    ("lubricant", "mu_ref_Pas"): (0.0, None, False, False),
    ("lubricant", "T_ref_K"): (0.0, None, False, False),
    ("lubricant", "B0"): (0.0, None, False, False),
    ("lubricant", "R0"): (0.0, 1.0, False, False),
    ("lubricant", "K0_prime"): (0.0, None, False, False),
    ("lubricant", "K00_GPa"): (0.0, None, False, False),
    ("lubricant", "n_power"): (0.0, 1.0, False, True),
    ("lubricant", "G_cr_kPa"): (0.0, None, False, False),
    ("lubricant", "alpha_per_GPa"): (0.0, None, False, False),
    ("lubricant", "conductivity_W_mK"): (0.0, None, False, False),
    ("lubricant", "density_kg_m3"): (0.0, None, False, False),
    ("lubricant", "specific_heat_J_kgK"): (0.0, None, False, False),
    ("roughness", "sigma_pinion_um"): (0.0, None, False, False),
    ("roughness", "sigma_wheel_um"): (0.0, None, False, False),
    ("roughness", "asperity_radius_um"): (0.0, None, False, False),
    ("roughness", "eta_beta_sigma"): (0.0, None, True, False),
    ("friction", "asperity_friction"): (0.0, None, True, False),
    ("friction", "limiting_shear_coeff"): (0.0, None, False, False),
    ("solver", "tolerance"): (0.0, 1.0, False, False),
    ("solver", "load_floor"): (0.0, 1.0, True, False),
    ("solver", "relaxation"): (0.0, 1.0, False, True),
}


def _check_range(where: str, key: str, v: float) -> None:
    bounds = _RANGES.get((where, key))
    if bounds is None:
        return
    lo, hi, lo_in, hi_in = bounds
    ok = (lo is None or v > lo or (lo_in and v == lo)) and (
        hi is None or v < hi or (hi_in and v == hi)
    )
    if not ok:
        left = "(-inf" if lo is None else ("[" if lo_in else "(") + f"{lo:g}"
        right = "inf)" if hi is None else f"{hi:g}" + ("]" if hi_in else ")")
        raise ModelError(f"{where}.{key} = {v!r}: must be in {left}, {right}")


_INTEGERS = {"max_iterations", "ehl_samples", "steps_per_period"}


@dataclass(frozen=True)
class TriboCase:
    """A tribo-dynamic case (SI units).

    Attributes
    ----------
    name, source, path : str
    pair : GearPair
        From the case's gear set.
    pinion_speed_rpm, torque_Nm : float
    mass_p_kg, mass_g_kg, inertia_p_kgm2, inertia_g_kgm2 : float
    mesh_damping_ratio : float
    half_backlash_m : float
        Half the stated backlash (the file gives the total gap on the line of action).
    bearing_stiffness_x_N_m, bearing_stiffness_y_N_m, bearing_damping_ratio : float
    lubrication : Lubrication
        Lubricant, roughness, friction constants, inlet temperature, thermal switch.
    solver : dict
        Keyword arguments for :func:`~models.dynamics.tribo_ehl_coupling.solve_tribo_dynamics`.
    steps_per_period : int or None
        RK4 steps per mesh period (None: automatic).
    """

    name: str
    source: str
    path: str
    pair: GearPair
    pinion_speed_rpm: float
    torque_Nm: float
    mass_p_kg: float
    mass_g_kg: float
    inertia_p_kgm2: float
    inertia_g_kgm2: float
    mesh_damping_ratio: float
    half_backlash_m: float
    bearing_stiffness_x_N_m: float
    bearing_stiffness_y_N_m: float
    bearing_damping_ratio: float
    lubrication: Lubrication
    solver: dict[str, Any]
    steps_per_period: int | None = None

    def dynamics(
        self, pinion_speed_rpm: float | None = None, *, rigid_bearings: bool = False
    ) -> TriboDynamics:
        """The six-DOF model (dry, no friction) at the case's or the given speed (rpm)."""
        rpm = self.pinion_speed_rpm if pinion_speed_rpm is None else float(pinion_speed_rpm)
        return build_tribo_dynamics(
            self.pair,
            torque_Nm=self.torque_Nm,
            pinion_speed_rpm=rpm,
            mass_p_kg=self.mass_p_kg,
            mass_g_kg=self.mass_g_kg,
            inertia_p_kgm2=self.inertia_p_kgm2,
            inertia_g_kgm2=self.inertia_g_kgm2,
            bearing_stiffness_x_N_m=self.bearing_stiffness_x_N_m,
            bearing_stiffness_y_N_m=self.bearing_stiffness_y_N_m,
            bearing_damping_ratio=self.bearing_damping_ratio,
            mesh_damping_ratio=self.mesh_damping_ratio,
            half_backlash_m=self.half_backlash_m,
            steps_per_period=self.steps_per_period,
            rigid_bearings=rigid_bearings,
        )


def shipped_tribo_cases() -> list[str]:
    """Names of the shipped tribo-dynamic cases."""
    return sorted(p.stem for p in _DIR.glob("*.toml"))


def tribo_case_path(name: str) -> Path:
    """Path of a shipped case by name."""
    p = _DIR / f"{name}.toml"
    if not p.is_file():
        raise ModelError(
            f"no shipped tribo case {name!r}; shipped: {', '.join(shipped_tribo_cases())}"
        )
    return p


def _value(where: str, key: str, v: Any) -> Any:
    if key == "thermal":
        if not isinstance(v, bool):
            raise ModelError(f"{where}.{key} = {v!r}: must be true or false")
        return v
    if key in _INTEGERS:
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            raise ModelError(f"{where}.{key} = {v!r}: must be a positive integer")
        return v
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ModelError(f"{where}.{key} = {v!r}: must be a finite number")
    return float(v)


def _section(doc: dict[str, Any], name: str) -> dict[str, Any]:
    d = doc.get(name, {})
    if not isinstance(d, dict):
        raise ModelError(f"[{name}] must be a table")
    schema = _SCHEMA[name]
    extra = sorted(set(d) - set(schema))
    if extra:
        raise ModelError(f"{name}.{extra[0]}: unknown key; allowed: {', '.join(sorted(schema))}")
    out: dict[str, Any] = {}
    for key, (attr, factor, required) in schema.items():
        if key not in d:
            if required:
                raise ModelError(f"{name}.{key}: required key missing")
            continue
        v = _value(name, key, d[key])
        if isinstance(v, float):
            _check_range(name, key, v)
        out[attr] = v * factor if isinstance(v, float) else v
    return out


def load_tribo_case(name_or_path: str | Path) -> TriboCase:
    """Load a tribo-dynamic case: a shipped name (``"seed-002-tribo"``) or a TOML file.

    Raises
    ------
    ModelError
        Unknown, missing or ill-typed keys, or values out of their physical range (positive
        masses, inertias, speed, torque, inlet temperature, viscosity, bulk modulus, roughness
        and asperity radius; ``0 < R0 < 1``; ``0 < n <= 1``; ``relaxation`` in (0, 1]; ...;
        the message names ``section.key`` and the file), an unknown gear set, or a file that is
        not TOML.
    """
    p = Path(name_or_path)
    if not p.suffix and not p.exists():
        p = tribo_case_path(str(name_or_path))
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ModelError(f"{p}: no such file") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ModelError(f"{p}: not a TOML file: {exc}") from exc
    try:
        extra = sorted(set(doc) - set(_SCHEMA) - {"case"})
        if extra:
            raise ModelError(
                f"{extra[0]}: unknown section; allowed: case, {', '.join(sorted(_SCHEMA))}"
            )
        case = doc.get("case", {})
        bad = sorted(set(case) - _CASE)
        if bad:
            raise ModelError(f"case.{bad[0]}: unknown key; allowed: {', '.join(sorted(_CASE))}")
        if not isinstance(case.get("gear_set"), str):
            raise ModelError("case.gear_set: required, the name or path of a gear set")
        gs_ref = case["gear_set"]
        gs_path = p.parent / gs_ref
        try:
            gear_set = load_gear_set(gs_path if gs_path.suffix == ".toml" else gs_ref)
        except GeometryError as exc:
            raise ModelError(f"case.gear_set: {exc}") from None
        s = {name: _section(doc, name) for name in _SCHEMA}
        lub = Lubricant(**s["lubricant"])
        rough = Roughness(**s["roughness"])
        solver = dict(s["solver"])
        thermal = bool(solver.pop("thermal", True))
        steps = solver.pop("steps_per_period", None)
        op = s["operating"]
        lubrication = Lubrication(
            lubricant=lub,
            roughness=rough,
            inlet_temperature_K=op.get("inlet_temperature_K"),
            thermal=thermal,
            **s["friction"],
        )
        return TriboCase(
            name=str(case.get("name", p.stem)),
            source=str(case.get("source", "")),
            path=str(p),
            pair=gear_set.pair,
            pinion_speed_rpm=op["pinion_speed_rpm"],
            torque_Nm=op["torque_Nm"],
            half_backlash_m=0.5 * s["mesh"]["backlash_m"],
            mesh_damping_ratio=s["mesh"]["mesh_damping_ratio"],
            lubrication=lubrication,
            solver=solver,
            steps_per_period=steps,
            **s["inertia"],
            **s["bearings"],
        )
    except ModelError as exc:
        raise ModelError(f"{p.name}: {exc}") from None


def solve_tribo_case(
    case: TriboCase, pinion_speed_rpm: float | None = None, **overrides: Any
) -> TriboSolution:
    """Run seed 002's decoupling loop for a case (speed in rpm; ``overrides`` go to the solver).

    Examples
    --------
    >>> case = load_tribo_case("seed-002-tribo")
    >>> round(case.torque_Nm / case.pair.base_radius(1)), case.half_backlash_m
    (1719, 3e-06)
    """
    rpm = case.pinion_speed_rpm if pinion_speed_rpm is None else float(pinion_speed_rpm)
    kwargs = {**case.solver, **overrides}
    return solve_tribo_dynamics(case.pair, case.dynamics(rpm), rpm, case.lubrication, **kwargs)

"""Geometry of an external spur gear pair: from z, m, alpha, b, shifts and diameters.

All lengths in m, angles in rad. The construction is the standard one of ISO 21771 / DIN 3960:

* reference radius ``r = z m / 2``, base radius ``r_b = r cos(alpha)``;
* operating pressure angle from the shifts (no-backlash meshing):
  ``inv(alpha') = inv(alpha) + 2 tan(alpha) (x1 + x2) / (z1 + z2)``, and the centre distance
  ``a' = a cos(alpha) / cos(alpha')`` with ``a = m (z1 + z2) / 2``; or, when the centre distance
  is given, ``alpha' = arccos(a cos(alpha) / a')`` (the shifts then fix the backlash);
* tip radius ``r_a = r + m (h_a* + x)`` and root radius ``r_f = r - m (h_f* - x)`` unless the
  diameters are given (test gears usually state them: FZG type C tips are shortened);
* transverse contact ratio
  ``eps = (sqrt(r_a1^2 - r_b1^2) + sqrt(r_a2^2 - r_b2^2) - a' sin(alpha')) / p_b`` with the base
  pitch ``p_b = pi m cos(alpha)``.

Geometry that cannot mesh is refused with a :class:`~models.errors.GeometryError` naming the
parameter: undercut, a pointed or too thin tip, a contact ratio below 1, a contact path reaching
below a base circle (involute interference), a tip running into the mating root (no clearance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from models.errors import GeometryError
from models.geometry.involute import inv, inv_inverse
from models.geometry.kinematics import mesh_frequency_Hz

__all__ = ["STEEL", "Gear", "GearPair", "Material"]

#: A tip thinner than this many modules is refused (ISO 21771 suggests >= 0.2 m for hardened
#: gears; 0.1 m keeps lightly shortened test gears while refusing pointed teeth).
MIN_TIP_THICKNESS_MODULES = 0.1


@dataclass(frozen=True)
class Material:
    """Material of a gear (SI units).

    Attributes
    ----------
    youngs_modulus_Pa : float
    poisson_ratio : float
    density_kg_m3 : float
    thermal_expansion_per_K : float
        Linear coefficient (1/K). Structural steel: about 1.1-1.2e-5 /K (seed 000 prints
        "3.43e-5 %", see SEED-NOTES 4).
    specific_heat_J_kgK : float
    conductivity_W_mK : float
    """

    youngs_modulus_Pa: float = 2.06e11
    poisson_ratio: float = 0.3
    density_kg_m3: float = 7850.0
    thermal_expansion_per_K: float = 1.15e-5
    specific_heat_J_kgK: float = 460.0
    conductivity_W_mK: float = 46.0

    def __post_init__(self) -> None:
        for name in ("youngs_modulus_Pa", "density_kg_m3", "specific_heat_J_kgK",
                     "conductivity_W_mK"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise GeometryError(f"material.{name}", v, "must be a finite number > 0")
        if not (0.0 <= self.poisson_ratio < 0.5):
            raise GeometryError("material.poisson_ratio", self.poisson_ratio,
                                "must lie in [0, 0.5)")
        if not (math.isfinite(self.thermal_expansion_per_K) and
                0 <= self.thermal_expansion_per_K < 1e-3):
            raise GeometryError("material.thermal_expansion_per_K",
                                self.thermal_expansion_per_K, "must lie in [0, 1e-3) 1/K")


STEEL = Material()


@dataclass(frozen=True)
class Gear:
    """One spur gear.

    Attributes
    ----------
    teeth : int
    profile_shift : float
        Profile shift coefficient x (-).
    tip_diameter_m, root_diameter_m : float or None
        Given diameters (m); None derives them from the addendum and dedendum coefficients.
    addendum_coeff, dedendum_coeff : float
        h_a* and h_f* of the basic rack (1.0 and 1.25 by default).
    root_fillet_coeff : float
        rho_f* of the basic rack (0.38 by default, ISO 53 profile A).
    material : Material
    bore_diameter_m : float or None
        Bore (m); used for rim/foundation and inertia. None: solid to 0.3 d.
    """

    teeth: int
    profile_shift: float = 0.0
    tip_diameter_m: float | None = None
    root_diameter_m: float | None = None
    addendum_coeff: float = 1.0
    dedendum_coeff: float = 1.25
    root_fillet_coeff: float = 0.38
    material: Material = field(default_factory=Material)
    bore_diameter_m: float | None = None


@dataclass(frozen=True)
class GearPair:
    """An external spur gear pair, pinion (1) driving wheel (2).

    Parameters
    ----------
    pinion, wheel : Gear
    module_m : float
        Module (m).
    pressure_angle_rad : float
        Reference (rack) pressure angle (rad).
    face_width_m : float
        Common face width (m).
    centre_distance_m : float or None
        Operating centre distance (m); None derives it from the shifts (zero backlash).
    name : str

    Notes
    -----
    Derived quantities are properties (computed once, cached in ``__post_init__``). Positions on
    the line of action are measured from T1, the tangent point of the line of action on the
    pinion's base circle; the wheel's tangent point T2 lies at ``a' sin(alpha')``.
    """

    pinion: Gear
    wheel: Gear
    module_m: float
    pressure_angle_rad: float
    face_width_m: float
    centre_distance_m: float | None = None
    name: str = ""

    def __post_init__(self) -> None:
        _check_positive("module_m", self.module_m)
        _check_positive("face_width_m", self.face_width_m)
        if not (0 < self.pressure_angle_rad < math.radians(35)):
            raise GeometryError("pressure_angle_rad", self.pressure_angle_rad,
                                "must lie in (0, 35 deg)")
        for who, g in (("pinion", self.pinion), ("wheel", self.wheel)):
            if int(g.teeth) != g.teeth or g.teeth < 5:
                raise GeometryError(f"{who}.teeth", g.teeth, "must be an integer >= 5")
        self._check_undercut()
        for key, value in self._derive().items():
            object.__setattr__(self, key, value)
        self._check_mesh()

    # --- construction -------------------------------------------------------------------
    def _derive(self) -> dict[str, float]:
        m, a0 = self.module_m, self.pressure_angle_rad
        z1, z2 = self.pinion.teeth, self.wheel.teeth
        x1, x2 = self.pinion.profile_shift, self.wheel.profile_shift
        a_ref = m * (z1 + z2) / 2
        if self.centre_distance_m is None:
            inv_w = float(inv(a0)) + 2 * math.tan(a0) * (x1 + x2) / (z1 + z2)
            alpha_w = float(inv_inverse(inv_w))
            a_w = a_ref * math.cos(a0) / math.cos(alpha_w)
        else:
            a_w = float(self.centre_distance_m)
            c = a_ref * math.cos(a0) / a_w
            if not (0 < c < 1):
                raise GeometryError("centre_distance_m", a_w,
                                    f"must exceed the base-radius sum {a_ref * math.cos(a0):.6g} m")
            alpha_w = math.acos(c)
        out: dict[str, float] = {"_a_w": a_w, "_alpha_w": alpha_w, "_a_ref": a_ref}
        for i, g in ((1, self.pinion), (2, self.wheel)):
            r = g.teeth * m / 2
            ra = (g.tip_diameter_m / 2 if g.tip_diameter_m is not None
                  else r + m * (g.addendum_coeff + g.profile_shift))
            rf = (g.root_diameter_m / 2 if g.root_diameter_m is not None
                  else r - m * (g.dedendum_coeff - g.profile_shift))
            out[f"_r{i}"] = r
            out[f"_rb{i}"] = r * math.cos(a0)
            out[f"_ra{i}"] = ra
            out[f"_rf{i}"] = rf
        return out

    def _check_undercut(self) -> None:
        # The rack's straight flank generates the whole profile down to the base circle only
        # while its addendum line (h_f* - rho_f*(1 - sin a) above the root) stays above the
        # interference point: x >= h_a0* - z sin^2(a) / 2 with h_a0* = h_f* - rho_f*(1 - sin a).
        a0 = self.pressure_angle_rad
        for who, g in (("pinion", self.pinion), ("wheel", self.wheel)):
            h_f = g.dedendum_coeff
            if g.root_diameter_m is not None:  # the cutter depth the given root implies
                h_f = (g.teeth * self.module_m - g.root_diameter_m) / (2 * self.module_m) \
                    + g.profile_shift
            h_a0 = h_f - g.root_fillet_coeff * (1 - math.sin(a0))
            x_min = h_a0 - g.teeth * math.sin(a0) ** 2 / 2
            if g.profile_shift < x_min - 1e-9:
                raise GeometryError(
                    f"{who}.profile_shift", g.profile_shift,
                    f"undercut: with {g.teeth} teeth it must be >= {x_min:.4f}",
                )

    def _check_mesh(self) -> None:
        m = self.module_m
        for i, who in ((1, "pinion"), (2, "wheel")):
            ra, rb, rf = self.tip_radius(i), self.base_radius(i), self.root_radius(i)
            if not ra > rb:
                raise GeometryError(f"{who}.tip_diameter_m", 2 * ra,
                                    f"must exceed the base diameter {2 * rb:.6g} m")
            if not rf < self.reference_radius(i) < ra:
                raise GeometryError(f"{who}.root_diameter_m", 2 * rf,
                                    "must be below the reference diameter, below the tip")
            sa = self.tip_thickness(i)
            if sa < MIN_TIP_THICKNESS_MODULES * m:
                raise GeometryError(
                    f"{who}.tip_diameter_m", 2 * ra,
                    f"tooth too thin at the tip: {sa * 1e3:.3f} mm < "
                    f"{MIN_TIP_THICKNESS_MODULES} m = {MIN_TIP_THICKNESS_MODULES * m * 1e3:.3f} mm",
                )
        for i, j, who in ((1, 2, "pinion"), (2, 1, "wheel")):
            clearance = self.centre_distance - self.tip_radius(i) - self.root_radius(j)
            if clearance < 0:
                raise GeometryError(f"{who}.tip_diameter_m", 2 * self.tip_radius(i),
                                    f"tip runs into the mating root: clearance "
                                    f"{clearance * 1e3:.3f} mm < 0")
        if self.start_of_contact <= 0:
            raise GeometryError("wheel.tip_diameter_m", 2 * self.tip_radius(2),
                                "involute interference: contact would start below the "
                                "pinion base circle")
        if self.end_of_contact >= self.line_of_action_length:
            raise GeometryError("pinion.tip_diameter_m", 2 * self.tip_radius(1),
                                "involute interference: contact would end below the "
                                "wheel base circle")
        if self.backlash_circumferential < -1e-9:
            raise GeometryError("centre_distance_m", self.centre_distance,
                                f"teeth would overlap: below the zero-backlash centre distance "
                                f"for these shifts (circumferential backlash "
                                f"{self.backlash_circumferential * 1e6:.1f} um)")
        if self.contact_ratio < 1.0:
            raise GeometryError("contact_ratio", self.contact_ratio,
                                "must be >= 1 for continuous meshing (check tip diameters "
                                "and centre distance)")

    # --- radii --------------------------------------------------------------------------
    def reference_radius(self, gear: int) -> float:
        """Reference radius ``z m / 2`` of gear 1 (pinion) or 2 (wheel) (m)."""
        return float(getattr(self, f"_r{gear}"))

    def base_radius(self, gear: int) -> float:
        """Base radius ``r cos(alpha)`` (m)."""
        return float(getattr(self, f"_rb{gear}"))

    def tip_radius(self, gear: int) -> float:
        """Tip radius (m)."""
        return float(getattr(self, f"_ra{gear}"))

    def root_radius(self, gear: int) -> float:
        """Root radius (m)."""
        return float(getattr(self, f"_rf{gear}"))

    def operating_pitch_radius(self, gear: int) -> float:
        """Operating pitch radius ``r_b / cos(alpha')`` (m)."""
        return self.base_radius(gear) / math.cos(self.operating_pressure_angle)

    def tip_thickness(self, gear: int) -> float:
        """Transverse tooth thickness on the tip circle (m).

        ``s_a = d_a (pi / (2 z) + 2 x tan(alpha) / z + inv(alpha) - inv(alpha_a))``,
        ``cos(alpha_a) = r_b / r_a``.
        """
        g = self.pinion if gear == 1 else self.wheel
        ra, rb = self.tip_radius(gear), self.base_radius(gear)
        a0 = self.pressure_angle_rad
        alpha_a = math.acos(rb / ra)
        half = (math.pi / (2 * g.teeth) + 2 * g.profile_shift * math.tan(a0) / g.teeth
                + float(inv(a0)) - float(inv(alpha_a)))
        return 2 * ra * half

    # --- mesh ---------------------------------------------------------------------------
    @property
    def centre_distance(self) -> float:
        """Operating centre distance a' (m)."""
        return float(self._a_w)  # type: ignore[attr-defined]

    @property
    def operating_pressure_angle(self) -> float:
        """Operating (working) pressure angle alpha' (rad)."""
        return float(self._alpha_w)  # type: ignore[attr-defined]

    @property
    def gear_ratio(self) -> float:
        """U = z2 / z1."""
        return self.wheel.teeth / self.pinion.teeth

    @property
    def base_pitch(self) -> float:
        """Base (normal) pitch ``pi m cos(alpha)`` (m)."""
        return math.pi * self.module_m * math.cos(self.pressure_angle_rad)

    @property
    def line_of_action_length(self) -> float:
        """Distance T1T2 between the base-circle tangent points, ``a' sin(alpha')`` (m)."""
        return self.centre_distance * math.sin(self.operating_pressure_angle)

    @property
    def start_of_contact(self) -> float:
        """Point A (start of contact, wheel tip) on the line of action, from T1 (m)."""
        return self.line_of_action_length - math.sqrt(self.tip_radius(2) ** 2
                                                      - self.base_radius(2) ** 2)

    @property
    def end_of_contact(self) -> float:
        """Point E (end of contact, pinion tip) on the line of action, from T1 (m)."""
        return math.sqrt(self.tip_radius(1) ** 2 - self.base_radius(1) ** 2)

    @property
    def pitch_point(self) -> float:
        """Pitch point C on the line of action, ``r_b1 tan(alpha')`` from T1 (m)."""
        return self.base_radius(1) * math.tan(self.operating_pressure_angle)

    @property
    def path_of_contact_length(self) -> float:
        """Length AE of the path of contact (m)."""
        return self.end_of_contact - self.start_of_contact

    @property
    def contact_ratio(self) -> float:
        """Transverse contact ratio ``AE / p_b`` (-)."""
        return self.path_of_contact_length / self.base_pitch

    @property
    def lowest_point_single_contact(self) -> float:
        """LPSTC (point B), ``E - p_b`` from T1 (m); for 1 <= eps < 2."""
        return self.end_of_contact - self.base_pitch

    @property
    def highest_point_single_contact(self) -> float:
        """HPSTC (point D), ``A + p_b`` from T1 (m); for 1 <= eps < 2."""
        return self.start_of_contact + self.base_pitch

    @property
    def backlash_circumferential(self) -> float:
        """Circumferential backlash on the operating pitch circle (m).

        ``j_t = p_w - s_w1 - s_w2`` with the operating pitch ``p_w = 2 pi r_w1 / z1`` and the
        tooth thicknesses ``s_wi = 2 r_wi (pi/(2 z_i) + 2 x_i tan(alpha)/z_i + inv(alpha)
        - inv(alpha'))``; zero when the centre distance comes from the shifts.
        """
        a0 = self.pressure_angle_rad
        aw = self.operating_pressure_angle
        total = 0.0
        for i, g in ((1, self.pinion), (2, self.wheel)):
            rw = self.operating_pitch_radius(i)
            s_w = 2 * rw * (math.pi / (2 * g.teeth) + 2 * g.profile_shift * math.tan(a0)
                            / g.teeth + float(inv(a0)) - float(inv(aw)))
            total += s_w
        pitch_w = 2 * math.pi * self.operating_pitch_radius(1) / self.pinion.teeth
        return pitch_w - total

    def mesh_period(self, pinion_speed_rpm: float) -> float:
        """Mesh period ``60 / (z1 n1)`` (s), the reciprocal of :meth:`mesh_frequency`."""
        return 1.0 / self.mesh_frequency(pinion_speed_rpm)

    def mesh_frequency(self, pinion_speed_rpm: float) -> float:
        """Mesh frequency ``z1 n1 / 60`` (Hz), by :func:`models.geometry.mesh_frequency_Hz`."""
        return float(mesh_frequency_Hz(pinion_speed_rpm, self.pinion.teeth))


    # --- positions on the line of action -----------------------------------------------
    def contact_radius(self, s_m: ArrayLike, gear: int) -> np.ndarray:
        """Radius of the contact point on gear 1 or 2 at positions ``s`` from T1 (m)."""
        s = np.asarray(s_m, float)
        rho = s if gear == 1 else self.line_of_action_length - s
        return np.hypot(self.base_radius(gear), rho)

    def roll_angle(self, s_m: ArrayLike, gear: int = 1) -> np.ndarray:
        """Roll angle of gear 1 or 2 at positions ``s`` from T1: ``rho / r_b`` (rad)."""
        s = np.asarray(s_m, float)
        rho = s if gear == 1 else self.line_of_action_length - s
        return rho / self.base_radius(gear)

    def position_from_roll_angle(self, roll_rad: ArrayLike, gear: int = 1) -> np.ndarray:
        """Inverse of :meth:`roll_angle`: position from T1 (m)."""
        rho = np.asarray(roll_rad, float) * self.base_radius(gear)
        return rho if gear == 1 else self.line_of_action_length - rho

    def curvature_radii(self, s_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Profile radii of curvature ``rho1 = s`` and ``rho2 = T1T2 - s`` (m)."""
        s = np.asarray(s_m, float)
        return s, self.line_of_action_length - s

    def surface_velocities(
        self, s_m: ArrayLike, pinion_speed_rpm: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Tangential (rolling) velocities of the flanks at the contact point (m/s).

        ``v1 = omega1 rho1``, ``v2 = omega2 rho2``; the sliding velocity is ``v1 - v2`` (zero at
        the pitch point, positive in recess), the sum velocity ``v1 + v2``.
        """
        w1 = pinion_speed_rpm * 2 * math.pi / 60
        w2 = w1 / self.gear_ratio
        r1, r2 = self.curvature_radii(s_m)
        return w1 * r1, w2 * r2

    def pair_positions(self, phase: ArrayLike, n_pairs: int = 3) -> np.ndarray:
        """Positions of ``n_pairs`` consecutive tooth pairs at mesh-cycle phases (m from T1).

        Pair ``k`` (``k = 0`` the most advanced, outgoing; higher ``k`` incoming) sits at
        ``A + (tau + n_pairs - 1 - k) p_b`` for a cycle phase ``tau`` in [0, 1); a pair is in
        the theoretical contact zone where ``A <= s <= E``.

        Returns
        -------
        numpy.ndarray
            Shape ``phase.shape + (n_pairs,)``.
        """
        tau = np.asarray(phase, float)[..., None]
        k = np.arange(n_pairs)
        return self.start_of_contact + (tau + (n_pairs - 1 - k)) * self.base_pitch


def _check_positive(name: str, value: float) -> None:
    if not (math.isfinite(value) and value > 0):
        raise GeometryError(name, value, "must be a finite number > 0")

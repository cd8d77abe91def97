"""Spur gear pair geometry against stated values and hand-derivable limits."""

import json
import math
import re
import tomllib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from models.errors import GeometryError
from models.geometry import Gear, GearPair, inv, inv_inverse, load_gear_set, shipped_gear_sets
from models.geometry.gear_sets import gear_set_path
from rigtools.schemas import iter_errors

DEG = math.pi / 180


def test_fzg_c_operating_pressure_angle_of_seed_000_table_1():
    # Seed 000 Table 1: alpha' = 22.439 deg for z 16/24, m 4.5, x 0.182/0.171 at the FZG
    # centre distance 91.5 mm. The table gives 3 decimals: tolerance 0.0005 deg.
    g = load_gear_set("fzg-c").pair
    assert math.degrees(g.operating_pressure_angle) == pytest.approx(22.439, abs=5e-4)
    # FZG type C transverse contact ratio is 1.44 (DIN ISO 14635-1 tables).
    assert g.contact_ratio == pytest.approx(1.44, abs=0.005)


def test_kahraman_contact_ratio_of_seed_003_table_3():
    # Seed 003 Table 3: theoretical contact ratio 1.75 (two decimals), standard tips.
    g = load_gear_set("kahraman-blankenship").pair
    assert g.contact_ratio == pytest.approx(1.75, abs=0.005)
    assert g.reference_radius(1) * 2 == pytest.approx(0.150)


def test_shift_derived_centre_distance_leaves_zero_backlash():
    g = GearPair(Gear(16, 0.182), Gear(24, 0.171), 4.5e-3, 20 * DEG, 14e-3)
    assert g.backlash_circumferential == pytest.approx(0.0, abs=1e-12)
    # ...and the same operating pressure angle comes back when that centre distance is given.
    h = GearPair(Gear(16, 0.182), Gear(24, 0.171), 4.5e-3, 20 * DEG, 14e-3,
                 centre_distance_m=g.centre_distance)
    assert h.operating_pressure_angle == pytest.approx(g.operating_pressure_angle, abs=1e-12)


def test_standard_pair_limits_by_hand():
    # No shifts: alpha' = alpha, a' = m (z1 + z2) / 2, pitch point at r1 sin(alpha).
    g = GearPair(Gear(20), Gear(40), 2e-3, 20 * DEG, 10e-3)
    assert g.operating_pressure_angle == pytest.approx(20 * DEG, abs=1e-14)
    assert g.centre_distance == pytest.approx(0.060)
    assert g.pitch_point == pytest.approx(0.020 * math.sin(20 * DEG))
    # Path of contact: A + p_b = HPSTC, E - p_b = LPSTC, both inside AE for 1 < eps < 2.
    assert g.start_of_contact < g.lowest_point_single_contact < g.pitch_point \
        < g.highest_point_single_contact < g.end_of_contact
    v1, v2 = g.surface_velocities(g.pitch_point, 1500)
    assert v1 == pytest.approx(v2, rel=1e-12)  # pure rolling at the pitch point


def test_positions_roll_angles_and_radii_are_consistent():
    g = load_gear_set("fzg-c").pair
    s = np.linspace(g.start_of_contact, g.end_of_contact, 52)  # seed 000: 52 points
    for gear in (1, 2):
        back = g.position_from_roll_angle(g.roll_angle(s, gear), gear)
        np.testing.assert_allclose(back, s, rtol=0, atol=1e-15)
    r1 = g.contact_radius(s, 1)
    assert r1[0] == pytest.approx(math.hypot(g.base_radius(1), g.start_of_contact))
    assert g.contact_radius(g.end_of_contact, 1) == pytest.approx(g.tip_radius(1))
    assert g.contact_radius(g.start_of_contact, 2) == pytest.approx(g.tip_radius(2))


def test_pair_positions_step_by_one_base_pitch():
    g = load_gear_set("kahraman-blankenship").pair
    pos = g.pair_positions(np.array([0.0, 0.5]), 3)
    np.testing.assert_allclose(np.diff(pos, axis=-1), -g.base_pitch)
    assert pos[0, -1] == pytest.approx(g.start_of_contact)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.01, 1.2))
def test_involute_inverse_round_trips(alpha):
    # Below ~0.01 rad tan(a) - a cancels to a few digits: no pressure angle lives there.
    assert float(inv_inverse(inv(alpha))) == pytest.approx(alpha, abs=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        (dict(pinion=Gear(12, 0.0)), "pinion.profile_shift"),  # undercut at 12 teeth, x = 0
        (dict(pinion=Gear(16, 0.182, tip_diameter_m=86e-3)), "pinion.tip_diameter_m"),  # pointed
        (dict(pinion=Gear(16, 0.182, tip_diameter_m=74e-3)), "contact_ratio"),  # eps < 1
        (dict(wheel=Gear(24, 0.171, root_diameter_m=112e-3)), "wheel.root_diameter_m"),
        (dict(centre_distance_m=80e-3), "centre_distance_m"),
        (dict(module_m=-1.0), "module_m"),
    ],
)
def test_impossible_geometry_is_refused_naming_the_parameter(kwargs, parameter):
    base = dict(pinion=Gear(16, 0.182), wheel=Gear(24, 0.171), module_m=4.5e-3,
                pressure_angle_rad=20 * DEG, face_width_m=14e-3)
    base.update(kwargs)
    with pytest.raises(GeometryError, match=rf"`{re.escape(parameter)}`"):
        GearPair(**base)


def test_negative_clearance_is_refused():
    with pytest.raises(GeometryError, match=r"`pinion.tip_diameter_m`.*(clearance|interference)"):
        GearPair(Gear(20), Gear(40, root_diameter_m=76.4e-3), 2e-3, 20 * DEG, 10e-3)


@pytest.mark.parametrize("name", shipped_gear_sets())
def test_every_shipped_gear_set_is_valid_against_the_schema_and_loads(name):
    doc = tomllib.loads(gear_set_path(name).read_text())
    assert iter_errors(doc, "gear_set.schema.json") == []
    gs = load_gear_set(name)
    assert gs.pair.contact_ratio > 1 and gs.source


def test_user_gear_set_with_an_unknown_key_names_file_and_key(tmp_path):
    p = tmp_path / "mine.toml"
    p.write_text(gear_set_path("fzg-c").read_text().replace("teeth = 16", "teeth = 16\ncolour = 1"))
    with pytest.raises(GeometryError, match=r"mine\.toml: pinion\.colour"):
        load_gear_set(p)
    assert json.dumps(iter_errors(tomllib.loads(p.read_text()), "gear_set.schema.json"))



def test_centre_distance_below_zero_backlash_is_refused():
    # FZG-C shifts need 91.499 mm; at 91.0 mm the teeth would overlap (reviewer's case).
    with pytest.raises(GeometryError, match=r"`centre_distance_m`.*teeth would overlap"):
        GearPair(Gear(16, 0.182, tip_diameter_m=82.46e-3), Gear(24, 0.171,
                 tip_diameter_m=118.36e-3), 4.5e-3, 20 * DEG, 14e-3, centre_distance_m=91.0e-3)

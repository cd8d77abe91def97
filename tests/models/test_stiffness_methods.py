"""Ishikawa (seed 000) against the potential-energy method (seed 003): where they differ, why.

Both model the tooth as a cantilever on a flexible foundation; they differ in the beam shape and
above all in the foundation:

* bending: Ishikawa's rectangle-plus-trapezoid against the true involute above a straight flank.
  The two agree within about 25 % along the path (closest at mid-profile), since both carry the
  same moment arm to the root.
* shear: the same energy integral over different sections; with the same shear coefficient
  (1.2) they agree within about 30 %, Ishikawa's trapezoid being wider near the tip.
* foundation: Ishikawa's term is the tilt of a rigid section on a half-plane under the bending
  moment only (24 F h_k^2 cos^2 w / (pi E b S_F^2)); Sainsot et al. (2004) fit the fillet
  foundation of real gears to FE and include the shear and normal load components, with a fillet
  much more compliant than a half-plane under a rigid section. Sainsot's term is 1.5 to 10 times
  larger, most where the load acts low on the tooth; it is most of the potential-energy
  compliance (about 70 % at the pitch point).

So Ishikawa without a contact term is much stiffer than the potential-energy pair (FZG-C mean
mesh stiffness about 33 against 16 N/(mm um)), and the difference is the foundation. ISO 6336's
c_gamma band (about 16-21 N/(mm um) for these pairs) lies between them; Ishikawa lands in it with
the Weber-Banaschek contact term, the potential-energy method without any contact term.
"""

import numpy as np
import pytest

from models.geometry import load_gear_set
from models.stiffness import ishikawa_deflection, tooth_compliance


@pytest.mark.parametrize("name", ["fzg-c", "kahraman-blankenship"])
@pytest.mark.parametrize("gear", [1, 2])
def test_beam_terms_agree_and_the_foundation_makes_the_difference(name, gear):
    g = load_gear_set(name).pair
    s = np.linspace(g.start_of_contact, g.end_of_contact, 21)
    ish = ishikawa_deflection(g, s, gear, shear_coefficient=1.2)  # unit load: m/N
    pe = tooth_compliance(g, s, gear)
    bending = (ish.delta_Br_m + ish.delta_Bt_m) / pe.bending_m_per_N
    shear = ish.delta_s_m / pe.shear_m_per_N
    foundation = ish.delta_G_m / pe.fillet_m_per_N
    assert np.all((bending > 0.7) & (bending < 1.35)), bending
    assert np.all((shear > 0.65) & (shear < 1.0)), shear
    assert np.all(foundation < 0.7), foundation
    # The foundation gap is largest where the load acts lowest on this tooth.
    low_on_tooth = 0 if gear == 1 else -1
    assert foundation[low_on_tooth] == foundation.min()

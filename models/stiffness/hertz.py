r"""Linearised Hertzian contact stiffness of a spur tooth pair (line contact).

Potential-energy tooth-pair models (Yang and Sun 1985, Yang and Lin 1987, Tian 2004, Chen and
Shao 2011; see :mod:`models.stiffness.potential_energy`) add to the beam and foundation
compliances of the two teeth a contact compliance that does not depend on the load or on the
position of the contact on the path:

.. math::

    k_h = \frac{\pi E b}{4 (1 - \nu^2)}

for two bodies of the same material (Young's modulus ``E``, Poisson's ratio ``nu``) in line
contact over the face width ``b``. Written with the contact modulus
``1/E* = (1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2`` it reads ``k_h = pi b E* / 2``, which is the form
used here for two materials; for equal materials ``E* = E / (2 (1 - nu^2))`` and the two
agree.

The true Hertzian approach of two cylinders is nonlinear (it grows like ``F ln(1/F)``) and
needs a reference depth (Weber-Banaschek; Johnson 1985, eq. 4.43); the linearised value is the
one the potential-energy literature uses and is what ``include_hertz=True`` adds in
:func:`models.stiffness.potential_energy.pair_compliance`. Per unit face width it is
``k_h / b = pi E* / 2``, about 180 N/(mm um) for steel (FZG-C: 2.51e9 N/m over 14 mm): an order
of magnitude stiffer than the teeth, so in series with them it lowers the mean mesh stiffness of
a steel pair by only about 5 % (FZG-C and Kahraman-Blankenship).

References
----------
.. [1] D. C. H. Yang, Z. S. Sun, "A rotary model for spur gear dynamics", ASME J. Mech.
   Transm. Autom. Des. 107 (1985) 529-535.
.. [2] D. C. H. Yang, J. Y. Lin, "Hertzian damping, tooth friction and bending elasticity in
   gear impact dynamics", ASME J. Mech. Transm. Autom. Des. 109 (1987) 189-196.
.. [3] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985 (ch. 4).
"""

from __future__ import annotations

import math

from models.errors import ModelError

__all__ = ["contact_modulus", "hertz_compliance", "hertz_stiffness"]


def _check(name: str, value: float, low: float, high: float) -> float:
    v = float(value)
    if not (math.isfinite(v) and low < v < high):
        raise ModelError(f"`{name}` must lie in ({low:g}, {high:g}), was {value!r}")
    return v


def contact_modulus(
    youngs_modulus_1_Pa: float,
    poisson_ratio_1: float,
    youngs_modulus_2_Pa: float | None = None,
    poisson_ratio_2: float | None = None,
) -> float:
    r"""Contact modulus ``E*`` of two elastic bodies (Pa).

    Parameters
    ----------
    youngs_modulus_1_Pa, poisson_ratio_1 : float
        Young's modulus (Pa) and Poisson's ratio (-) of body 1.
    youngs_modulus_2_Pa, poisson_ratio_2 : float or None
        The same for body 2; None takes body 1's values.

    Returns
    -------
    float
        ``E*`` (Pa).

    Notes
    -----
    .. math:: \frac{1}{E^*} = \frac{1 - \nu_1^2}{E_1} + \frac{1 - \nu_2^2}{E_2}

    (Johnson 1985, ch. 4.)

    Examples
    --------
    >>> round(contact_modulus(2.06e11, 0.3) / 1e9, 3)  # E / (2 (1 - nu^2)) for equal bodies
    113.187
    """
    e1 = _check("youngs_modulus_1_Pa", youngs_modulus_1_Pa, 0.0, math.inf)
    n1 = _check("poisson_ratio_1", poisson_ratio_1, -1.0, 0.5)
    e2 = e1 if youngs_modulus_2_Pa is None else _check("youngs_modulus_2_Pa",
                                                       youngs_modulus_2_Pa, 0.0, math.inf)
    n2 = n1 if poisson_ratio_2 is None else _check("poisson_ratio_2", poisson_ratio_2,
                                                   -1.0, 0.5)
    return 1.0 / ((1 - n1 * n1) / e1 + (1 - n2 * n2) / e2)


def hertz_stiffness(
    face_width_m: float,
    youngs_modulus_1_Pa: float,
    poisson_ratio_1: float,
    youngs_modulus_2_Pa: float | None = None,
    poisson_ratio_2: float | None = None,
) -> float:
    r"""Linearised Hertzian stiffness of a tooth pair in line contact (N/m).

    Parameters
    ----------
    face_width_m : float
        Length of the contact line, the common face width (m).
    youngs_modulus_1_Pa, poisson_ratio_1 : float
        Young's modulus (Pa) and Poisson's ratio (-) of the pinion.
    youngs_modulus_2_Pa, poisson_ratio_2 : float or None
        The same for the wheel; None takes the pinion's values.

    Returns
    -------
    float
        ``k_h`` (N/m), independent of load and contact position.

    Notes
    -----
    .. math:: k_h = \frac{\pi b E^*}{2} \;=\; \frac{\pi E b}{4 (1 - \nu^2)}
              \quad\text{(equal materials)}

    Yang and Sun (1985); used unchanged by Yang and Lin (1987), Tian (2004) and Chen and Shao
    (2011).

    Examples
    --------
    Kahraman-Blankenship steel pair, b = 20 mm (E = 206 GPa, nu = 0.3):

    >>> round(hertz_stiffness(0.020, 2.06e11, 0.3) / 1e9, 4)  # 1e9 N/m
    3.5559
    """
    b = _check("face_width_m", face_width_m, 0.0, math.inf)
    return math.pi * b * contact_modulus(youngs_modulus_1_Pa, poisson_ratio_1,
                                         youngs_modulus_2_Pa, poisson_ratio_2) / 2.0


def hertz_compliance(
    face_width_m: float,
    youngs_modulus_1_Pa: float,
    poisson_ratio_1: float,
    youngs_modulus_2_Pa: float | None = None,
    poisson_ratio_2: float | None = None,
) -> float:
    """Linearised Hertzian compliance ``1 / k_h`` of a tooth pair (m/N).

    Parameters as :func:`hertz_stiffness`.

    Examples
    --------
    >>> round(hertz_compliance(0.020, 2.06e11, 0.3) * 1e10, 3)  # 1e-10 m/N
    2.812
    """
    return 1.0 / hertz_stiffness(face_width_m, youngs_modulus_1_Pa, poisson_ratio_1,
                                 youngs_modulus_2_Pa, poisson_ratio_2)

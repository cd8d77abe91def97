"""Thermal effects on spur gear meshing: contact temperature, thermal expansion, and the
thermoelastic-backlash mesh stiffness with its critical compensation gap (seeds 000 and 001).
"""

__all__: list[str] = []

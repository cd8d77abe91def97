"""Fixtures of the calibration tests (defined in :mod:`calibration_cases`)."""

from calibration_cases import pair, secant_fit

__all__ = ["pair", "secant_fit"]

"""Argument types of the subcommands: a bad value is a usage error (exit 2), named by argparse.

``type=positive_float`` and the like; argparse prints ``rigtools SUBCOMMAND: error: argument
--OPTION: <message>`` and exits with code 2.
"""

from __future__ import annotations

import argparse
import math

__all__ = ["finite_float", "int_at_least", "non_negative_float", "positive_float"]


def finite_float(text: str) -> float:
    """Argument type: a finite number."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return v


def positive_float(text: str) -> float:
    """Argument type: a finite number > 0."""
    v = finite_float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return v


def non_negative_float(text: str) -> float:
    """Argument type: a finite number >= 0."""
    v = finite_float(text)
    if not v >= 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return v


def int_at_least(text: str, least: int) -> int:
    """Argument type (with ``least`` bound): an integer >= ``least``."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if v < least:
        raise argparse.ArgumentTypeError(f"must be an integer >= {least}, got {text!r}")
    return v

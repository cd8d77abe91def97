"""Argument types of the subcommands: a bad value is a usage error (exit 2), named by argparse.

``type=positive_float`` and the like; argparse prints ``rigtools SUBCOMMAND: error: argument
--OPTION: <message>`` and exits with code 2. Every bound is checked here, when the command
line is parsed, before any file is read or written.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path

__all__ = [
    "finite_float",
    "float_in_range",
    "int_at_least",
    "int_in_range",
    "non_negative_float",
    "output_path",
    "positive_float",
]


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


def float_in_range(text: str, lo: float, hi: float) -> float:
    """Argument type (with bounds): a finite number with ``lo <= value <= hi``."""
    v = finite_float(text)
    if not lo <= v <= hi:
        raise argparse.ArgumentTypeError(f"must be from {lo:g} to {hi:g}, got {text!r}")
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


def int_in_range(text: str, least: int, most: int) -> int:
    """Argument type (with bounds): an integer with ``least <= value <= most``."""
    v = int_at_least(text, least)
    if v > most:
        raise argparse.ArgumentTypeError(f"must be an integer <= {most}, got {text!r}")
    return v


def output_path(*suffixes: str) -> Callable[[str], str]:
    """Argument type: a file to write, whose suffix (case aside) is one of ``suffixes``.

    An existing folder passes, so that the subcommand can say it is a folder
    (:func:`rigtools.cli.common.output_problem`, exit 3 like any path that cannot be written).
    """
    accepted = tuple(s.lower() for s in suffixes)

    def check(text: str) -> str:
        p = Path(text)
        if p.is_dir():
            return text
        suffix = p.suffix.lower()
        if suffix not in accepted:
            found = f"suffix {p.suffix!r}" if p.suffix else "no suffix"
            raise argparse.ArgumentTypeError(
                f"{text!r} has {found}; accepted: {', '.join(accepted)}")
        return text

    return check

"""Fixtures of the calibration tests.

``pair`` and ``secant_fit`` are defined in :mod:`calibration_cases`; the two that build and
parse the text of a campaign file with a ``[calibration]`` block are defined here.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable

import pytest
from calibration_cases import pair, secant_fit, toml_lines

from rigtools.calibration import CalibrationConfig, parse_calibration_block

__all__ = ["campaign_text", "pair", "parse_campaign_text", "secant_fit"]

#: A one-run campaign up to its ``[calibration]`` header (line 9: a block starts on line 10).
_CAMPAIGN_HEAD = """\
[campaign]
name = "x"
gear_set = "fzg-c"

[[run]]
id = "a"
file = "a.mcap"

[calibration]
"""


@pytest.fixture
def campaign_text() -> Callable[[str], str]:
    """``campaign_text(block)``: a one-run campaign file whose ``[calibration]`` is ``block``.

    ``block``'s first line is line 10 of the file; it may add sub-tables after its keys.
    """
    return lambda block: _CAMPAIGN_HEAD + block


@pytest.fixture
def parse_campaign_text() -> Callable[[str], CalibrationConfig]:
    """``parse_campaign_text(text)``: the ``[calibration]`` block of a campaign file's text.

    Errors name ``c.toml`` and the line of the key in ``text``.
    """
    def parse(text: str) -> CalibrationConfig:
        doc = tomllib.loads(text)
        return parse_calibration_block(doc.get("calibration"), source="c.toml",
                                       line_of=toml_lines(text))

    return parse

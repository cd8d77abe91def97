"""Shared fixtures: the third-party data folder, skipped cleanly when absent.

:data:`REALDATA` is the one definition of where it lives; tests that list its files when they
are collected (``parametrize``) import it from :mod:`realdata_path`, every other test takes the
:func:`realdata` fixture.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from realdata_path import REALDATA


@pytest.fixture(scope="session")
def realdata() -> Path:
    """``../shared/realdata`` (third-party files, never copied into the project)."""
    if not REALDATA.is_dir():
        pytest.skip(f"third-party data folder {REALDATA} is absent")
    return REALDATA

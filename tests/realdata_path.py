"""Where the third-party data folder lives: ``../shared/realdata`` (never copied here).

The one definition; ``tests/conftest.py`` builds the :func:`realdata` fixture on it, and tests
that list its files when they are collected (``parametrize``) import :data:`REALDATA`.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["PROJECT_ROOT", "REALDATA"]

PROJECT_ROOT = Path(__file__).resolve().parents[1]
REALDATA = PROJECT_ROOT.parent / "shared" / "realdata"

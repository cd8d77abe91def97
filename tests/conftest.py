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


#: Test folders whose session fixtures (a whole pipeline run, a calibration) several files share:
#: under pytest-xdist each runs on one worker, so those fixtures are computed once.
SHARED_FIXTURE_FOLDERS = ("calibration", "pipeline", "report")
#: Files in those folders that use none of the shared fixtures and are long on their own (the
#: run-up calibrations): each is its own group, so they run beside the folder, not after it.
OWN_GROUP_FILES = ("calibration/test_sbc_runup.py", "calibration/test_runup_calibration.py")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Group the tests for ``--dist loadgroup``: a shared-fixture folder, else the file."""
    if not config.pluginmanager.hasplugin("xdist"):
        return
    tests = Path(__file__).resolve().parent
    for item in items:
        path = Path(str(item.path)).resolve()
        try:
            rel = path.relative_to(tests)
        except ValueError:      # doctests of the packages
            rel = path
        top = rel.parts[0] if len(rel.parts) > 1 else ""
        own = rel.as_posix() in OWN_GROUP_FILES or top not in SHARED_FIXTURE_FOLDERS
        group = rel.as_posix() if own else top
        item.add_marker(pytest.mark.xdist_group(name=group))

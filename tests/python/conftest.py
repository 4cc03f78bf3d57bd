"""Without ../shared/data the suite reports CTest's skip code 77, and fails with CI=true (where the data
is always present), as the C++ data tests do (tests/doctest_main.cpp). Checked before collection: an
exit raised while importing a test file would count as a collection error instead."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EUROC = Path(os.environ.get("VOCA_SHARED_DATA", ROOT.parent / "shared" / "data")) / "euroc_v101_micro" / "mav0"


def pytest_sessionstart(session):
    if not EUROC.is_dir():
        ci = os.environ.get("CI") == "true"
        pytest.exit(f"{EUROC}: shared data missing{' (CI=true: a failure)' if ci else ''}", returncode=1 if ci else 77)

"""Shared fixtures: the repository's test data and the `mdsurf` command line to compare with."""

import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"


@pytest.fixture(scope="session")
def data():
    """The folder of real test trajectories (tests/data)."""
    return DATA


@pytest.fixture(scope="session")
def cli():
    """The `mdsurf` binary: $MDSURF_BIN (scripts/test sets it), else target/release/mdsurf."""
    path = os.environ.get("MDSURF_BIN") or ROOT / "target" / "release" / "mdsurf"
    path = shutil.which(str(path))
    if path is None:
        if os.environ.get("MDSURF_BIN"):
            pytest.fail(f"MDSURF_BIN={os.environ['MDSURF_BIN']} is not an executable")
        pytest.skip("no mdsurf binary: build it with `cargo build --release` or set MDSURF_BIN")
    return path

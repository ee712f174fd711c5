"""Shared fixtures: the checkout's root and the `rtk` binary the module is
compared with (built here if the test run did not build it already)."""

import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def rtk_bin():
    """The `rtk` binary of this checkout, release build."""
    subprocess.check_call(
        ["cargo", "build", "--release", "-q", "-p", "rtk-host", "--bin", "rtk"], cwd=ROOT
    )
    exe = ROOT / "target" / "release" / "rtk"
    assert exe.is_file(), exe
    return exe

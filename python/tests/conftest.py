"""Shared paths and helpers of the Python package's tests."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
SCENES = EXAMPLES / "scenes"
PINOCCHIO = ROOT / "tests" / "fixtures" / "pinocchio"


def _find_cli() -> Path | None:
    """The `satsim` binary: $SATSIM_BIN, else the workspace's release or debug build, else PATH."""
    env = os.environ.get("SATSIM_BIN")
    if env:
        return Path(env)
    for profile in ("release", "debug"):
        p = ROOT / "target" / profile / "satsim"
        if p.is_file():
            return p
    found = shutil.which("satsim")
    return Path(found) if found else None


@pytest.fixture(scope="session")
def cli() -> Path:
    """The command line to compare against. CI sets $SATSIM_BIN (a missing binary then fails);
    elsewhere the tests that need it are skipped when there is none."""
    path = _find_cli()
    if path is None:
        pytest.skip("no `satsim` binary: run `cargo build --release` or set SATSIM_BIN")
    assert path.is_file(), f"SATSIM_BIN={path} does not exist"
    return path


@pytest.fixture
def python_sigint():
    """Python's own SIGINT handler for the test: a runner started in the background (a shell's
    `cmd &`) inherits SIGINT ignored, and then `_thread.interrupt_main()`, the tests' Ctrl-C,
    does nothing."""
    import signal

    before = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)

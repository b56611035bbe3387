"""Shared paths and fixtures of the fistage Python tests: the repository root (the
shipped scenarios and robots), found from this file."""

import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture
def root():
    return ROOT


@pytest.fixture
def ctrl_c():
    """Ctrl-C raises KeyboardInterrupt during the test, as in an interactive
    interpreter, even when the test process was started with SIGINT ignored
    (a background job of a non-interactive shell)."""
    import signal

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)

"""Shared paths of the fistage Python tests: the repository root (the
shipped scenarios and robots), found from this file."""

import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture
def root():
    return ROOT

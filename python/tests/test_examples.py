"""The examples run headless and say what they found."""

import pathlib
import subprocess
import sys

import pytest

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def run(name, *args):
    done = subprocess.run([sys.executable, str(EXAMPLES / name), *args],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_fig05b_example_plots(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "fig05b.png"
    text = run("fig05b.py", str(out))
    assert "limit cycle 69." in text, text
    assert out.stat().st_size > 10_000


def test_parallel_example_maps_runs():
    text = run("parallel_damping.py")
    assert text.count("steady peak-to-peak") == 4, text

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


def test_stribeck_example_fits_its_csv(tmp_path):
    text = run("stribeck_fit.py", str(tmp_path / "fss.csv"))
    lines = {line.split()[0]: line for line in text.splitlines()}
    assert set(lines) == {"f_c", "f_s", "v_s", "sigma2"}, text
    assert float(lines["f_c"].split()[1]) == pytest.approx(5.1, rel=0.02)


def test_stability_map_example(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "map.png"
    text = run("stability_map.py", str(out))
    stable = int(text.split()[0])
    # Fig. 6b/8: the FI stage is stable only in a pocket of the (k, c) plane.
    assert 0 < stable < 64, text
    assert out.stat().st_size > 5_000


def test_tolerance_example(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "tolerance.png"
    text = run("tolerance.py", str(out))
    words = text.split()
    estimate, low, high = (float(words[i].strip("[],")) for i in (2, 5, 6))
    assert 0.0 < low <= estimate <= high < 1.0, text
    assert "most influential" in text
    assert out.stat().st_size > 5_000

"""Runs in parallel: the Fig. 5b stage's steady oscillation against the
servo damping c, one process per run (scenarios pickle).

    python python/examples/parallel_damping.py
"""

import concurrent.futures
import pathlib

import fistage


def peak_to_peak(scenario):
    return scenario.run().summary["signals"]["encoder.position"]["peak_to_peak"]


if __name__ == "__main__":
    root = pathlib.Path(__file__).resolve().parents[2]
    base = fistage.load(root / "scenarios/paper/fig05b_fi.toml")
    dampings = [50.0, 100.0, 200.0, 400.0]
    variants = [base.with_overrides({"controller.c": c}) for c in dampings]
    with concurrent.futures.ProcessPoolExecutor() as pool:
        for c, p in zip(dampings, pool.map(peak_to_peak, variants)):
            print("c = %6.1f N s/m: steady peak-to-peak %.3e m" % (c, p))

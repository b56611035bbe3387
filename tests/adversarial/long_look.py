#!/usr/bin/env python3
"""The simulated verdicts of a tolerance analysis against much longer runs.

Usage: python3 tests/adversarial/long_look.py SCENARIO [SECONDS]

Runs the scenario's [robust] analysis (analysis = "simulation") with the
Python package, then every stage of the population again for SECONDS
(default 32, 16 times a 2 s run) and counts the stages whose tracking error
still oscillates at the end: peak-to-peak over the last 2 s above 1e-9 m and
at least half the 2 s before. Prints P(oscillating) with its interval, the
persistent fraction, and the stages on which the two disagree. Exit status 1
when the persistent fraction lies outside the interval.
"""

import os
import re
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy

import fistage


def main():
    path = sys.argv[1]
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 32.0
    scenario = fistage.load(path)
    started = time.time()
    study = scenario.robust()
    p = study.summary["p_oscillating"]
    low, high = p["ci95"]
    print("P(oscillating) %.4f, 95%% interval %.4f to %.4f, %s undetermined (%.0f s)"
          % (p["estimate"], low, high, study.summary.get("undetermined_simulated"), time.time() - started))
    text = open(path).read()
    text, found = re.subn(r"^duration\s*=.*$", "duration = %r" % seconds, text, count=1, flags=re.M)
    if not found:
        sys.exit("%s: no top-level duration to lengthen" % path)
    longer = fistage.Scenario.from_toml(text, base_dir=os.path.dirname(os.path.abspath(path)))
    drawn = [c for c in study.columns if c not in
             ("sample", "stable_linear", "max_real_eig", "stable_sim", "amplitude", "yaw_amplitude",
              "bistable", "refused")]

    def persists(point):
        r = longer.with_overrides({c: point[c] for c in drawn}).run()
        t, e = r.time, r["controller.error"]
        last = numpy.ptp(e[t >= seconds - 2.0])
        before = numpy.ptp(e[(t >= seconds - 4.0) & (t < seconds - 2.0)])
        return bool(last > 1e-9 and last >= 0.5 * before)

    started = time.time()
    with ThreadPoolExecutor(os.cpu_count() or 1) as pool:
        persistent = list(pool.map(persists, study.points))
    n = len(persistent)
    fraction = sum(persistent) / n
    verdicts = [point["stable_sim"] for point in study.points]
    print("persistent at %g s: %d of %d, %.4f (%.0f s)" % (seconds, sum(persistent), n, fraction,
                                                          time.time() - started))
    print("called oscillating, settled by then: %d; called stable, oscillating then: %d; "
          "undetermined: %d, of them persistent: %d"
          % (sum(1 for v, q in zip(verdicts, persistent) if v is False and not q),
             sum(1 for v, q in zip(verdicts, persistent) if v is True and q),
             sum(1 for v in verdicts if v is None),
             sum(1 for v, q in zip(verdicts, persistent) if v is None and q)))
    inside = low <= fraction <= high
    print("the persistent fraction is %s the interval" % ("inside" if inside else "OUTSIDE"))
    sys.exit(0 if inside else 1)


if __name__ == "__main__":
    main()

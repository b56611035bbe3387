"""A small tolerance analysis of the Fig. 5b stage with FI: the scenario's
[robust] table (manufacturing spread of f_S, sigma2, the isolator's k_x and
c_x, and the servo damping) sampled 256 times, the probability that the
stage is linearly unstable with its 95% interval, which parameter matters
most, and a histogram of the largest real part drawn with matplotlib.

    python python/examples/tolerance.py [OUT.png]
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402

import fistage  # noqa: E402

root = pathlib.Path(__file__).resolve().parents[2]
population = fistage.load(root / "scenarios/robust/fig05b_population.toml")
study = population.robust(samples=256)
p = study.summary["p_unstable_linear"]
low, high = p["ci95"]
print("P(unstable) = %.3f, 95%% interval [%.3f, %.3f] over %d stages" % (p["estimate"], low, high, p["n"]))
top = max(study.summary["sensitivity"], key=lambda s: s["index"])
print("most influential: %s (|rank correlation| %.2f)" % (top["parameter"], top["index"]))
growth = study["max_real_eig"]
fig, ax = plt.subplots(figsize=(6, 4))
ax.hist(growth[numpy.isfinite(growth)], bins=32, color="tab:blue")
ax.axvline(0.0, color="k", linewidth=1)
ax.set_xlabel("largest real part of the eigenvalues (1/s)")
ax.set_ylabel("stages")
ax.set_title("Fig. 5b stage with FI, 256 stages with manufacturing spread")
out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path("tolerance.png")
fig.savefig(out, dpi=100, bbox_inches="tight")
print("histogram in", out)

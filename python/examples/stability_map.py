"""A linear stability map of the Fig. 5b stage with FI over the servo gains
k and c: the verdict of the eigenvalues at the slipping equilibrium (20 mm/s)
at every grid point, drawn with matplotlib.

    python python/examples/stability_map.py [OUT.png]
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402

import fistage  # noqa: E402

root = pathlib.Path(__file__).resolve().parents[2]
base = fistage.load(root / "scenarios/paper/fig05b_fi.toml")
ks = numpy.geomspace(1e4, 1e6, 8)
cs = numpy.geomspace(10.0, 1000.0, 8)
growth = numpy.full((len(cs), len(ks)), numpy.nan)
for i, c in enumerate(cs):
    for j, k in enumerate(ks):
        modes = base.with_overrides({"controller.k": k, "controller.c": c}).modes()
        if modes["verdict"] != "undetermined":
            growth[i, j] = modes["max_real_part"]
stable = int(numpy.sum(growth < 0))
fig, ax = plt.subplots(figsize=(6, 5))
mesh = ax.pcolormesh(ks, cs, numpy.sign(growth), cmap="coolwarm", shading="nearest", vmin=-1, vmax=1)
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("k [N/m]")
ax.set_ylabel("c [N s/m]")
ax.set_title("slipping equilibrium: blue stable, red unstable")
out = sys.argv[1] if len(sys.argv) > 1 else "stability_map.png"
fig.savefig(out, dpi=100)
print("%d of %d points linearly stable, map in %s" % (stable, growth.size, out))

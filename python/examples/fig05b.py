"""Fig. 5b with the friction isolator: run it and plot the table position.

    python python/examples/fig05b.py [OUT.png]
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import fistage  # noqa: E402

root = pathlib.Path(__file__).resolve().parents[2]
result = fistage.load(root / "scenarios/paper/fig05b_fi.toml").run()
fig, ax = plt.subplots(figsize=(8, 4))
ax.plot(result.time, result["encoder.position"] * 1e6, label="table (encoder)")
ax.plot(result.time, result["bearing_x.q"] * 1e6, label="bearing")
ax.set_xlabel("time [s]")
ax.set_ylabel("position [um]")
ax.set_title(result.summary["title"])
ax.legend()
out = sys.argv[1] if len(sys.argv) > 1 else "fig05b.png"
fig.savefig(out, dpi=100)
print("limit cycle %.2f um peak-to-peak, plot in %s"
      % (result.summary["signals"]["encoder.position"]["peak_to_peak"] * 1e6, out))

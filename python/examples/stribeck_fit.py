"""A Stribeck fit from a CSV file: writes a lab-style f_ss(v) curve (paper
Eq. 30 with Table 1's parameters and 20 mN of force noise) to a CSV file,
reads it back with numpy and fits f_c, f_s, v_s and sigma2 with intervals.

    python python/examples/stribeck_fit.py [DATA.csv]
"""

import sys

import numpy

import fistage

path = sys.argv[1] if len(sys.argv) > 1 else "fss.csv"
f_c, f_s, v_s, sigma2 = 5.1, 6.5, 0.0167, 14.2
v = numpy.concatenate([-numpy.geomspace(2e-4, 0.2, 25), numpy.geomspace(2e-4, 0.2, 25)])
force = (f_c + (f_s - f_c) * numpy.exp(-(v / v_s) ** 2)) * numpy.sign(v) + sigma2 * v
force += 0.02 * numpy.random.default_rng(1).standard_normal(v.size)
numpy.savetxt(path, numpy.column_stack([v, force]), delimiter=",",
              header="velocity_m_per_s,force_N", comments="")

data = numpy.loadtxt(path, delimiter=",", skiprows=1)
fit = fistage.identify.stribeck(data[:, 0], data[:, 1], loss="huber")
for name in fit.parameters:
    entry = fit[name]
    low, high = entry["ci95"]
    print("%-6s %.5g %s  (95%%: %.5g .. %.5g)" % (name, entry["value"], entry["unit"], low, high))

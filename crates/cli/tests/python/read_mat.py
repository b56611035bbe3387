"""Reads trajectory.mat with scipy.io.loadmat and checks it against
trajectory.csv of the same run: every signal a column vector equal to its
CSV column, named by a valid MATLAB identifier, and the `signals` table of
variable names, signal names and units matching the CSV header.

Usage: read_mat.py RUN_FOLDER; prints one line per checked variable count."""

import csv
import re
import sys

import numpy as np
import scipy.io

folder = sys.argv[1]
mat = scipy.io.loadmat(folder + "/trajectory.mat")
with open(folder + "/trajectory.csv", newline="") as f:
    rows = list(csv.reader(f))
header, data = rows[0], np.array(rows[1:], dtype=float)
table = mat["signals"]
assert table.shape == (len(header), 3), table.shape
identifier = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,62}$")
names = set()
for k, column_title in enumerate(header):
    variable, original, unit = (str(cell[0]) if cell.size else "" for cell in table[k])
    assert identifier.match(variable), variable
    assert variable not in names, variable
    names.add(variable)
    assert column_title == "%s [%s]" % (original, unit), (column_title, original, unit)
    values = mat[variable]
    assert values.shape == (data.shape[0], 1), (variable, values.shape)
    assert np.array_equal(values[:, 0], data[:, k]), variable
print("checked %d variables of %d samples" % (len(header), data.shape[0]))

"""Rewrites a record CSV (t_s, f_servo_N, x_m) as MAT-files the way scipy
writes them: version 5 uncompressed, version 5 compressed (MATLAB's -v7),
with the position in nm, as row vectors in the compressed one."""
import sys

import numpy as np
import scipy.io

source, out_plain, out_compressed = sys.argv[1:4]
data = np.loadtxt(source, delimiter=",", skiprows=1)
t, f, x = data[:, 0], data[:, 1], data[:, 2]
scipy.io.savemat(out_plain, {"t_s": t[:, None], "f_servo_N": f[:, None], "x_nm": x[:, None] * 1e9})
scipy.io.savemat(
    out_compressed,
    {"t_s": t, "f_servo_N": f, "x_m": x, "note": "a record"},
    do_compression=True,
    oned_as="row",
)
print("wrote", out_plain, out_compressed)

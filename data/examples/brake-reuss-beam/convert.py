#!/usr/bin/python3
"""Converts the Brake-Reuss beam hammer record (HammerImpact.mat, GPL-3.0, see
SOURCE.md) to jointlab's CSV test-file format: metadata comments, a time column
in seconds and three acceleration channels in m/s^2.

Usage: /usr/bin/python3 convert.py /path/to/HammerImpact.mat hammer_impact.csv
"""
import sys

import numpy as np
from scipy.io import loadmat


def main(src, dst):
    d = loadmat(src, squeeze_me=True, struct_as_record=False)["HIdata"]
    t = np.asarray(d.time, dtype=float).ravel()
    chans = [np.asarray(getattr(d, n), dtype=float).ravel() for n in ("acc1", "acc2", "acc3")]
    fs = 1.0 / np.median(np.diff(t))
    with open(dst, "w") as f:
        f.write("# test: Brake-Reuss beam hammer impact (Tribomechadynamics Lab, Rice University)\n")
        f.write("# source: HammerImpact.mat, GPL-3.0, see SOURCE.md\n")
        f.write(f"# fs: {fs:.6f}\n")
        f.write("time,acc1 [m/s^2],acc2 [m/s^2],acc3 [m/s^2]\n")
        for k in range(len(t)):
            f.write(f"{t[k]:.8f},{chans[0][k]:.7g},{chans[1][k]:.7g},{chans[2][k]:.7g}\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

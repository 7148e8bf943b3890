#!/usr/bin/env python3
"""An open-loop record of an actuator with backlash, for `diagnose --figures`.

The plant: a staircase command u (holds of 15-40 samples, levels uniform in -2..2) passes through
play of total width 0.8, then y(t) = 0.85 y(t-1) + 0.3 x(t-1), plus AR(1) noise (pole 0.7,
innovation s.d. 0.05). The user's nominal is what they would bring: an ARX [2 2 1] fitted by least
squares on the whole record and simulated from the input. Writes DIR/rec.csv (time,u,y) and
DIR/sim.csv (time,y). Seed 7.

Reference only; the product and its tests never need Python.
    python3 -m venv v && v/bin/pip install numpy scipy
    v/bin/python scripts/backlash_record.py DIR
    mpmwatch diagnose --recorded DIR/rec.csv --simulated DIR/sim.csv --inputs u --outputs y \\
        --report DIR/d.json --corrected DIR/c.csv --figures DIR
"""
import os
import sys

import numpy as np
from scipy.signal import lfilter


def play(u, width):
    half, out, trace = width / 2, u[0], []
    for v in u:
        if v > out + half:
            out = v - half
        elif v < out - half:
            out = v + half
        trace.append(out)
    return np.array(trace)


def main(out_dir):
    rng = np.random.default_rng(7)
    n = 2000
    u, t = np.zeros(n), 0
    while t < n:
        hold = rng.integers(15, 40)
        u[t : t + hold] = rng.uniform(-2, 2)
        t += hold
    y = lfilter([0, 0.3], [1, -0.85], play(u, 0.8))
    y += lfilter([1], [1, -0.7], rng.standard_normal(n)) * 0.05
    rows = np.arange(3, n)
    design = np.column_stack([y[rows - 1], y[rows - 2], u[rows - 1], u[rows - 2]])
    theta, *_ = np.linalg.lstsq(design, y[rows], rcond=None)
    s = np.zeros(n)
    s[:3] = y[:3]
    for k in range(3, n):
        s[k] = theta[0] * s[k - 1] + theta[1] * s[k - 2] + theta[2] * u[k - 1] + theta[3] * u[k - 2]
    time = np.arange(n, dtype=float)
    os.makedirs(out_dir, exist_ok=True)
    save = lambda name, cols, head: np.savetxt(
        os.path.join(out_dir, name), np.column_stack(cols), delimiter=",", header=head, comments="", fmt="%.9g"
    )
    save("rec.csv", [time, u, y], "time,u,y")
    save("sim.csv", [time, s], "time,y")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: backlash_record.py DIR")
    main(sys.argv[1])

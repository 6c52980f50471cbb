#!/usr/bin/env python3
"""Writes a jittered CSV for `ctid fit --irregular` (docs/cli-estimation.md, decision 0034).

The system (2 + 0.3 p) / (1 + 0.4 p + 0.25 p^2) driven by a held (ZOH) random input, logged
at about 20 Hz with +-30 % jitter on every stamp, 1 % of the samples missing and 1 % of the
stamps repeated; the response is exact on each interval (matrix exponential of the augmented
matrix), plus white output noise of standard deviation NOISE.

usage: /usr/bin/python3 scripts/irregular_example.py OUT.csv [SEED] [NOISE]
"""
import sys

import numpy as np
from scipy.linalg import expm


def main():
    out = sys.argv[1]
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 1
    noise = float(sys.argv[3]) if len(sys.argv) > 3 else 0.05
    rng = np.random.default_rng(seed)
    h, n = 0.05, 2000
    stamps = []
    k = 0
    while len(stamps) < n:
        stamp = k * h + 0.3 * h * rng.uniform(-1.0, 1.0)
        if k == 0 or rng.uniform() >= 0.01:
            stamps.append(stamp)
        k += 1
    t = np.array(stamps)
    for j in range(1, n - 1):
        if rng.uniform() < 0.01:
            t[j] = t[j - 1]
    u = rng.standard_normal(n)
    # Controllable form of (0.3 p + 2) / (0.25 p^2 + 0.4 p + 1) = (1.2 p + 8) / (p^2 + 1.6 p + 4).
    a = np.array([[0.0, 1.0], [-4.0, -1.6]])
    b = np.array([0.0, 1.0])
    c = np.array([8.0, 1.2])
    x = np.zeros(2)
    y = np.empty(n)
    for j in range(n):
        if j > 0 and t[j] > t[j - 1]:
            m = np.zeros((3, 3))
            m[:2, :2] = a
            m[:2, 2] = b
            e = expm(m * (t[j] - t[j - 1]))
            x = e[:2, :2] @ x + e[:2, 2] * u[j - 1]
        y[j] = c @ x
    y += noise * rng.standard_normal(n)
    with open(out, "w") as f:
        f.write("t,u,y\n")
        for j in range(n):
            f.write(f"{t[j]:.6f},{u[j]:.9g},{y[j]:.9g}\n")


if __name__ == "__main__":
    main()

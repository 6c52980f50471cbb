#!/usr/bin/env python3
"""A NumPy/SciPy reference of the additive SRIVC iteration, written for issue 14's speed
comparison (benchmarks/ratio_table.py): González et al., eq. (29), open loop, zero initial
conditions, the same filters as ctid's (docs/algorithms/refined-iv.md):

- submodel i is B_i/A_i with A_i = 1 + a_i1 p + ... + a_in p^n and B_i = b_i0 + ... + b_im p^m
  (ascending coefficients), theta_i = [a_i1 .. a_in, b_i0 .. b_im];
- the input is held (ZOH) and the residual output y~_i = y - sum_l x_l + x_i is interpolated
  linearly between samples (FOH), every filter running from rest at the first sample;
- regressor  phi_i  = [-p^k/A_i y~_i (k = 1..n), p^j/A_i u (j = 0..m)], left side 1/A_i y~_i,
  instrument zeta_i = [-p^k B_i/A_i^2 u,           p^j/A_i u],
  all submodels solved together with one right-hand column per submodel, theta_i taken from
  its own column (the block diagonal of eq. 27), columns scaled to unit norm;
- stop when the largest ||d a_i|| / ||a_i|| or ||d b_i|| / ||b_i|| falls below the tolerance.

The filtering is scipy.signal.lfilter on the exact ZOH / FOH discretisation (augmented matrix
exponential); a FOH filter from rest differs from lfilter's zero initial state by a free
response, which is added. No code is shared with ctid.

Command line: reference_srivc.py DATA.csv START.json prints a JSON object with the estimated
submodels, the iterations and the seconds spent loading and fitting. DATA.csv has a header
row and columns t, u, y; START.json is an additive_model file (ctid's format).
"""

import json
import sys
import time
import warnings

import numpy as np
from scipy import linalg, signal


def _quietly(function, *arguments):
    # tf2ss and ss2tf warn when a numerator's leading coefficients are ~0 (a strictly proper
    # filter); they are exact zeros up to rounding and harmless to lfilter.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", signal.BadCoefficients)
        return function(*arguments)


def _descending(ascending, length):
    row = np.zeros(length)
    coefficients = np.asarray(ascending, dtype=float)[::-1]
    row[length - len(coefficients):] = coefficients
    return row


def _discrete_filters(numerators, denominator, h, hold):
    """numerators[r](p) / denominator(p) (ascending lists), discretised exactly for a held
    (zoh) or linearly interpolated (foh) signal. Returns (rows of b, a, free) for lfilter;
    `free` is None for zoh, else (b, a, length) of the FOH start correction."""
    size = len(denominator)
    num = np.array([_descending(n, size) for n in numerators])
    a_c, b_c, c_c, d_c = _quietly(signal.tf2ss, num, _descending(denominator, size))
    n = a_c.shape[0]
    if hold == "zoh":
        m = np.zeros((n + 1, n + 1))
        m[:n, :n] = a_c
        m[:n, n:] = b_c
        f = linalg.expm(m * h)
        phi, gamma = f[:n, :n], f[:n, n:]
        b_d, a_d = _quietly(signal.ss2tf, phi, gamma, c_c, d_c)
        return b_d, a_d, None
    # x_{k+1} = phi x_k + g1 u_k + g2 (u_{k+1} - u_k); with z_k = x_k - g2 u_k the recursion is
    # causal in u_k, and from rest (x_0 = 0) z_0 = -g2 u_0.
    m = np.zeros((n + 2, n + 2))
    m[:n, :n] = a_c
    m[:n, n:n + 1] = b_c
    m[n, n + 1] = 1.0 / h
    f = linalg.expm(m * h)
    phi, g1, g2 = f[:n, :n], f[:n, n:n + 1], f[:n, n + 1:n + 2]
    b_d, a_d = _quietly(signal.ss2tf, phi, phi @ g2 + g1 - g2, c_c, c_c @ g2 + d_c)
    # The free response C phi^k g2 lasts until phi^k has decayed below rounding.
    radius = max(np.abs(np.linalg.eigvals(phi))) if n > 0 else 0.0
    length = None if radius >= 1.0 - 1e-15 else int(np.ceil(np.log(1e-18) / np.log(radius))) + 2
    b_free, a_free = _quietly(signal.ss2tf, phi, g2, c_c, np.zeros_like(d_c))
    return b_d, a_d, (b_free, a_free, length)


def filter_bank(x, numerators, denominator, h, hold):
    """Rows numerators[r](p)/denominator(p) x, exact at the samples, from rest at x's first
    sample (x held for zoh, linearly interpolated for foh)."""
    b_rows, a, free = _discrete_filters(numerators, denominator, h, hold)
    out = np.empty((len(numerators), len(x)))
    for r in range(len(numerators)):
        out[r] = signal.lfilter(b_rows[r], a, x)
    if free is not None and x[0] != 0.0:
        b_free, a_free, length = free
        length = len(x) if length is None else min(len(x), length)
        impulse = np.zeros(length + 1)
        impulse[0] = 1.0
        for r in range(len(numerators)):
            # impulse response g_k = C phi^(k-1) g2, so C phi^k g2 = g_(k+1)
            out[r, :length] -= x[0] * signal.lfilter(b_free[r], a_free, impulse)[1:]
    return out


def _reflect_unstable(a):
    """A = 1 + a_1 p + ... with roots in the right half-plane mirrored (A kept at A(0) = 1)."""
    coefficients = np.concatenate([[1.0], a])
    roots = np.roots(coefficients[::-1])
    if not np.any(roots.real > 0):
        return a
    roots = np.where(roots.real > 0, -roots.conj(), roots)
    mirrored = np.real(np.poly(roots))[::-1]  # ascending, leading (highest) coefficient 1
    return (mirrored / mirrored[0])[1:]


def _relative_change(before, after):
    largest = 0.0
    whole = max(np.linalg.norm(np.concatenate([np.concatenate(t) for t in before])), 1e-300)
    for (a0, b0), (a1, b1) in zip(before, after):
        for x0, x1 in ((a0, a1), (b0, b1)):
            if len(x0) == 0:
                continue
            size = np.linalg.norm(x0)
            largest = max(largest, np.linalg.norm(x1 - x0) / (size if size > 1e-12 * whole
                                                              else whole))
    return largest


def additive_srivc(u, y, h, start, max_iterations=100, tolerance=1e-10):
    """The iteration of eq. (29) from `start`, a list of (denominator, numerator) ascending
    coefficient lists with denominator[0] = 1. Returns a dict with "submodels" (the same
    form), "iterations" and "converged"."""
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    theta = [(np.asarray(d[1:], dtype=float), np.asarray(n, dtype=float)) for d, n in start]
    converged = False
    iteration = 0
    for iteration in range(1, max_iterations + 1):
        u_banks = []
        outputs = []
        instruments = []
        for a, b in theta:
            den = np.concatenate([[1.0], a])
            n, m = len(a), len(b)
            bank = filter_bank(u, [[0.0] * j + [1.0] for j in range(m)], den, h, "zoh")
            u_banks.append(bank)
            outputs.append(b @ bank)
            # -p^k B / A^2 u, k = 1..n
            squared = np.polynomial.polynomial.polymul(den, den)
            numerators = [np.polynomial.polynomial.polymul([0.0] * k + [1.0], b)
                          for k in range(1, n + 1)]
            instruments.append(-filter_bank(u, numerators, squared, h, "zoh"))
        total = np.sum(outputs, axis=0)
        z_columns, phi_columns, left = [], [], []
        for i, (a, b) in enumerate(theta):
            den = np.concatenate([[1.0], a])
            n = len(a)
            residual = y - total + outputs[i]
            y_bank = filter_bank(residual, [[0.0] * k + [1.0] for k in range(n + 1)], den, h,
                                 "foh")
            left.append(y_bank[0])
            phi_columns.extend([-y_bank[1:], u_banks[i]])
            z_columns.extend([instruments[i], u_banks[i]])
        z = np.vstack(z_columns)      # p x N
        phi = np.vstack(phi_columns)  # p x N
        upsilon = np.vstack(left)     # K x N
        sz = np.sqrt(np.einsum("ij,ij->i", z, z))
        sp = np.sqrt(np.einsum("ij,ij->i", phi, phi))
        matrix = (z / sz[:, None]) @ (phi / sp[:, None]).T
        rhs = (z / sz[:, None]) @ upsilon.T
        solution = np.linalg.solve(matrix, rhs) / sp[:, None]
        following = []
        offset = 0
        for i, (a, b) in enumerate(theta):
            block = solution[offset:offset + len(a) + len(b), i]
            following.append((_reflect_unstable(block[:len(a)]), block[len(a):]))
            offset += len(a) + len(b)
        change = _relative_change(theta, following)
        theta = following
        if change < tolerance:
            converged = True
            break
    return {
        "submodels": [{"denominator_ascending": [1.0, *a.tolist()],
                       "numerator_ascending": b.tolist()} for a, b in theta],
        "iterations": iteration,
        "converged": converged,
    }


def read_start(path):
    with open(path) as f:
        model = json.load(f)
    return [(s["denominator_ascending"], s["numerator_ascending"]) for s in model["submodels"]]


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: reference_srivc.py DATA.csv START.json")
    began = time.perf_counter()
    table = np.loadtxt(argv[1], delimiter=",", skiprows=1, comments="#")
    t, u, y = table[:, 0], table[:, 1], table[:, 2]
    h = (t[-1] - t[0]) / (len(t) - 1)
    loaded = time.perf_counter()
    result = additive_srivc(u, y, h, read_start(argv[2]))
    done = time.perf_counter()
    result["seconds_load"] = loaded - began
    result["seconds_fit"] = done - loaded
    json.dump(result, sys.stdout)
    print()


if __name__ == "__main__":
    main(sys.argv)

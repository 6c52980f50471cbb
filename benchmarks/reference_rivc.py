#!/usr/bin/env python3
"""A NumPy/SciPy reference of the refined instrumental variable estimator with an ARMA noise
model (RIVC: the hybrid Box-Jenkins model, a continuous plant B/A and discrete noise C/D).
No code is shared with ctid; the continuous filters are those of reference_srivc.py.

The model: y(t_k) = B(p)/A(p) u(t_k) + C(q^-1)/D(q^-1) e_k, with A = 1 + a_1 p + ... + a_n p^n
and B = b_0 + ... + b_m p^m (ascending coefficients), beta = [a_1..a_n, b_0..b_m], and
D = 1 + d_1 q^-1 + ... + d_P q^-P, C = 1 + c_1 q^-1 + ... + c_Q q^-Q.

One step beta -> beta' of the iteration, on one record, every filter starting from rest at the
first sample, the input held between samples (ZOH) and the output interpolated linearly (FOH):

1. the noise-free model output x = B/A u and the output error xi = y - x;
2. the noise model at beta: (D, C) minimising sum_k e_k^2 with e = (D/C) xi run from zero
   pre-sample values, C kept invertible -- here scipy.optimize.least_squares on e(d, c) with its
   analytic Jacobian (de/dd_i is the i-step delay of xi/C, de/dc_j minus that of e/C), a
   trust-region method stopped only by its step size, started from a Hannan-Rissanen estimate
   (a long autoregression's residual standing in for e);
3. the continuous filters at A: p^k/A y (k = 0..n), p^j/A u (j = 0..m) and the instrument's
   p^k B/A^2 u (k = 1..n), the last formed as one filter of the held input with numerator
   p^k B and denominator A^2;
4. every one of those sequences passed through the discrete D/C from rest;
5. regressor [-p^k/A y (k = 1..n), p^j/A u], instrument [-p^k B/A^2 u, p^j/A u] (both
   prefiltered), left side 1/A y (prefiltered); beta' solves the square normal equations of
   the instrument, with every column scaled to unit norm first.

Right-half-plane roots of A' are mirrored. The iteration stops when the larger of
||a' - a|| / ||a|| and ||b' - b|| / ||b|| falls below the tolerance. As ctid does, `rivc` first
runs plain SRIVC (reference_srivc.additive_srivc with one submodel) from the start and starts
the iteration above from that estimate; the returned noise model is the one fitted at the final
beta.
"""

import pathlib
import sys

import numpy as np
from scipy import optimize, signal

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import reference_srivc  # noqa: E402


def _delayed(x, k):
    """x delayed by k samples, zeros before the first."""
    out = np.zeros_like(x)
    if k < len(x):
        out[k:] = x[:len(x) - k]
    return out


def _polynomials(theta, ar_order):
    d = np.concatenate([[1.0], theta[:ar_order]])
    c = np.concatenate([[1.0], theta[ar_order:]])
    return d, c


def hannan_rissanen(v, ar_order, ma_order):
    """A rough ARMA start: the innovations taken as the residual of a long autoregression, then
    v regressed on its own past and on that residual's past. Returns theta = [d_1.., c_1..]."""
    v = np.asarray(v, dtype=float)
    if ar_order + ma_order == 0:
        return np.zeros(0)
    innovations = v
    if ma_order > 0:
        long_order = min(max(30, 3 * (ar_order + ma_order)), len(v) // 8)
        design = np.column_stack([-_delayed(v, i) for i in range(1, long_order + 1)])
        innovations = v - design @ np.linalg.lstsq(design, v, rcond=None)[0]
    columns = [-_delayed(v, i) for i in range(1, ar_order + 1)]
    columns += [_delayed(innovations, j) for j in range(1, ma_order + 1)]
    theta = np.linalg.lstsq(np.column_stack(columns), v, rcond=None)[0]
    # An MA part that is not invertible is no usable start: drop it.
    c = np.concatenate([[1.0], theta[ar_order:]])
    if ma_order > 0 and np.any(np.abs(np.roots(c[::-1])) <= 1.0):
        theta[ar_order:] = 0.0
    return theta


def arma_least_squares(v, ar_order, ma_order, start=None):
    """The prediction-error ARMA(P, Q) of v: minimises ||(D/C) v||^2 (from rest) over
    D = [1, d_1..d_P], C = [1, c_1..c_Q]. Returns (D, C, innovations, result of least_squares).
    """
    v = np.asarray(v, dtype=float)
    p, q = ar_order, ma_order
    if p + q == 0:
        return np.ones(1), np.ones(1), v.copy(), None
    theta0 = hannan_rissanen(v, p, q) if start is None else np.asarray(start, dtype=float)

    def residual(theta):
        d, c = _polynomials(theta, p)
        return signal.lfilter(d, c, v)

    def jacobian(theta):
        d, c = _polynomials(theta, p)
        e = signal.lfilter(d, c, v)
        w = signal.lfilter([1.0], c, v)
        s = signal.lfilter([1.0], c, e)
        columns = [_delayed(w, i) for i in range(1, p + 1)]
        columns += [-_delayed(s, j) for j in range(1, q + 1)]
        return np.column_stack(columns)

    fit = optimize.least_squares(residual, theta0, jac=jacobian, method="trf", xtol=1e-15,
                                 ftol=None, gtol=None, max_nfev=2000)
    # Near the minimum the sum of squares is flat to rounding some 1e-8 away from it in the
    # coefficients (its change is quadratic in theirs), so a method that compares sums stops
    # there. The gradient J'e is still accurate there: its zero is found from that point
    # (Powell's hybrid method, finite-difference derivatives).
    # hybr often ends with "not making good progress" once the gradient is at rounding, so
    # its answer is judged by the gradient and the sum, not by its flag.
    def gradient(theta):
        return jacobian(theta).T @ residual(theta)

    polished = optimize.root(gradient, fit.x, method="hybr", options={"xtol": 1e-15})
    theta = fit.x
    if (np.all(np.isfinite(polished.x))
            and np.linalg.norm(gradient(polished.x)) < np.linalg.norm(gradient(theta))
            and np.sum(residual(polished.x) ** 2) <= np.sum(residual(theta) ** 2) * (1 + 1e-12)):
        theta = polished.x
    fit.x = theta
    d, c = _polynomials(theta, p)
    if q > 0 and np.any(np.abs(np.roots(c[::-1])) <= 1.0):
        raise RuntimeError("the ARMA least-squares fit left C not invertible")
    return d, c, signal.lfilter(d, c, v), fit


def _monomial(k, then=None):
    row = np.zeros(k + 1)
    row[k] = 1.0
    return row if then is None else np.polynomial.polynomial.polymul(row, then)


def rivc_step(u, y, h, a, b, ar_order, ma_order):
    """One pass of the iteration at beta = (a, b). Returns (a', b', D, C), D and C fitted at
    beta."""
    n, m = len(a), len(b) - 1
    den = np.concatenate([[1.0], a])
    model_output = reference_srivc.filter_bank(u, [b], den, h, "zoh")[0]
    d, c, _, _ = arma_least_squares(y - model_output, ar_order, ma_order)
    y_bank = reference_srivc.filter_bank(y, [_monomial(k) for k in range(n + 1)], den, h, "foh")
    u_bank = reference_srivc.filter_bank(u, [_monomial(j) for j in range(m + 1)], den, h, "zoh")
    squared = np.polynomial.polynomial.polymul(den, den)
    x_bank = reference_srivc.filter_bank(u, [_monomial(k, b) for k in range(1, n + 1)],
                                         squared, h, "zoh")
    y_bank, u_bank, x_bank = (signal.lfilter(d, c, bank, axis=1)
                              for bank in (y_bank, u_bank, x_bank))
    phi = np.vstack([-y_bank[1:], u_bank])
    zeta = np.vstack([-x_bank, u_bank])
    sz = np.linalg.norm(zeta, axis=1)
    sp = np.linalg.norm(phi, axis=1)
    matrix = (zeta / sz[:, None]) @ (phi / sp[:, None]).T
    rhs = (zeta / sz[:, None]) @ y_bank[0]
    beta = np.linalg.solve(matrix, rhs) / sp
    return reference_srivc._reflect_unstable(beta[:n]), beta[n:], d, c


def _change(a0, b0, a1, b1):
    whole = max(np.linalg.norm(np.concatenate([a0, b0])), 1e-300)
    largest = 0.0
    for x0, x1 in ((a0, a1), (b0, b1)):
        if len(x0) == 0:
            continue
        size = np.linalg.norm(x0)
        largest = max(largest, np.linalg.norm(x1 - x0) / (size if size > 1e-12 * whole else whole))
    return largest


def rivc(u, y, h, start_denominator, start_numerator, ar_order, ma_order, max_iterations=500,
         tolerance=1e-12, srivc_first=True):
    """RIVC from the start A = start_denominator, B = start_numerator (ascending, A[0] = 1).
    Returns a dict: "parameters" [a_1..a_n, b_0..b_m], "ar" D, "ma" C (fitted at the final
    parameters), "iterations", "converged", and "srivc" (the first stage's result, or None)."""
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    first = None
    if srivc_first:
        first = reference_srivc.additive_srivc(
            u, y, h, [(start_denominator, start_numerator)], max_iterations=max_iterations,
            tolerance=tolerance)
        start_denominator = first["submodels"][0]["denominator_ascending"]
        start_numerator = first["submodels"][0]["numerator_ascending"]
    a = np.asarray(start_denominator[1:], dtype=float)
    b = np.asarray(start_numerator, dtype=float)
    converged = False
    iteration = 0
    for iteration in range(1, max_iterations + 1):
        a_next, b_next, _, _ = rivc_step(u, y, h, a, b, ar_order, ma_order)
        change = _change(a, b, a_next, b_next)
        a, b = a_next, b_next
        if change < tolerance:
            converged = True
            break
    model_output = reference_srivc.filter_bank(u, [b], np.concatenate([[1.0], a]), h, "zoh")[0]
    d, c, _, _ = arma_least_squares(y - model_output, ar_order, ma_order)
    return {"parameters": np.concatenate([a, b]), "ar": d, "ma": c, "iterations": iteration,
            "converged": converged, "srivc": first}

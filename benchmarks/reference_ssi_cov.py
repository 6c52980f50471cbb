#!/usr/bin/env python3
"""A NumPy/SciPy reference of covariance-driven SSI, written for issue 38's speed comparison
(benchmarks/ssi_cov_benchmark.py). The same estimator as `ctid oma --method ssi-cov`
(docs/oma.md, decision 0030), every order's poles from one SVD:

- each channel's mean removed; correlations R_i = (1/N) sum_k y_{k+i} y_ref,k^T for the lags
  i = 1 .. 2p - 1 (biased estimate), all of them from one zero-padded real FFT per channel;
- the block Hankel matrix H (p l x p r) with block (i, j) = R_{i+j+1} (i, j from 0);
- the thin SVD of H (numpy.linalg.svd), O = U_n S_n^(1/2) of the largest order, the numerical
  rank (singular values above 1e-12 times the largest: an order beyond it is taken at it);
- one QR of O_up (the first (p - 1) l rows), S = Q^T O_down; for each order n = 2, 4, ..,
  max_order, A_n = R_n^-1 S_n (upper left n x n blocks), its eigenvalues lambda and vectors psi;
- a pole is kept when Im lambda > 0, |lambda| < 1 and 0 < zeta < max_damping, with
  s = ln(lambda)/h, f = |s|/(2 pi), zeta = -Re s/|s|, and shape C psi scaled so that its entry
  of largest modulus is exactly 1.

For `ctid oma --method fdd` the same file has the spectral side, `first_singular_value`: the
output spectral matrix by scipy.signal.csd (Welch, periodic Hann window, half overlap, each
segment's mean removed, one-sided density: the conventions docs/oma.md gives) and at every line
its singular values and first singular vector (numpy.linalg.svd over all lines at once). The
peak picking is not repeated.

No code is shared with ctid. Command line: reference_ssi_cov.py DATA.npy H BLOCK_ROWS
MAX_ORDER prints a JSON object with every order's poles (frequency, damping ratio) and the
seconds spent loading and identifying; reference_ssi_cov.py --fdd DATA.npy H SEGMENT_LENGTH
prints the first singular value at every line. DATA.npy holds one column per channel (every
channel is a reference).
"""

import json
import sys
import time

import numpy as np
from scipy import linalg, signal


def correlations(y, lags, references=None):
    """R_1 .. R_lags (lags x l x r) of the N x l record y."""
    n, l = y.shape
    references = list(range(l)) if references is None else list(references)
    centred = y - y.mean(axis=0)
    # N + lags points hold every lag up to `lags` without wrap-around.
    size = 1 << int(np.ceil(np.log2(n + lags)))
    spectra = np.fft.rfft(centred, size, axis=0)
    cross = spectra[:, :, None] * np.conj(spectra[:, None, references])
    return np.fft.irfft(cross, size, axis=0)[1:lags + 1] / n


def hankel(r, block_rows):
    """The block Hankel matrix of R_1 .. R_{2p-1} (p block rows and columns)."""
    _, l, m = r.shape
    p = block_rows
    out = np.empty((p * l, p * m))
    for i in range(p):
        out[i * l:(i + 1) * l] = r[i:i + p].transpose(1, 0, 2).reshape(l, p * m)
    return out


def ssi_cov(y, h, block_rows, max_order, max_damping=0.2, references=None):
    """Every order's poles: a list of (order, [(frequency_hz, damping_ratio, shape), ...]) with
    the poles of each order sorted by frequency."""
    l = y.shape[1]
    big = hankel(correlations(y, 2 * block_rows - 1, references), block_rows)
    u, sv, _ = np.linalg.svd(big, full_matrices=False)
    rank = int(np.count_nonzero(sv > 1e-12 * sv[0]))
    o = u[:, :max_order] * np.sqrt(sv[:max_order])
    q, r = np.linalg.qr(o[:-l])
    s = q.T @ o[l:]
    orders = []
    for n in range(2, max_order + 1, 2):
        k = min(n, rank)
        a = linalg.solve_triangular(r[:k, :k], s[:k, :k])
        lambdas, vectors = np.linalg.eig(a)
        shapes = o[:l, :k] @ vectors
        poles = []
        for lam, shape in zip(lambdas, shapes.T):
            if not (lam.imag > 0 and abs(lam) < 1):
                continue
            pole = np.log(lam) / h
            wn = abs(pole)
            zeta = -pole.real / wn
            if not 0 < zeta < max_damping:
                continue
            largest = np.argmax(np.abs(shape))
            poles.append((wn / (2 * np.pi), zeta, shape / shape[largest]))
        poles.sort(key=lambda pole: pole[0])
        orders.append((n, poles))
    return orders


def first_singular_value(y, h, segment_length):
    """Frequencies [Hz], the first singular value of the spectral matrix and its first singular
    vector at every line."""
    channels = y.T
    f, g = signal.csd(channels[:, None, :], channels[None, :, :], fs=1.0 / h, window="hann",
                      nperseg=segment_length, noverlap=segment_length // 2, detrend="constant",
                      scaling="density", axis=-1)
    u, sv, _ = np.linalg.svd(np.moveaxis(g, -1, 0))
    return f, sv[:, 0], u[:, :, 0]


def main():
    began = time.perf_counter()
    if sys.argv[1] == "--fdd":
        y = np.load(sys.argv[2])
        loaded = time.perf_counter()
        f, s1, _ = first_singular_value(y, float(sys.argv[3]), int(sys.argv[4]))
        done = time.perf_counter()
        print(json.dumps({"frequency_hz": f.tolist(), "first_singular_value": s1.tolist(),
                          "seconds_load": loaded - began, "seconds_spectrum": done - loaded}))
        return
    y = np.load(sys.argv[1])
    h, block_rows, max_order = float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    loaded = time.perf_counter()
    orders = ssi_cov(y, h, block_rows, max_order)
    done = time.perf_counter()
    print(json.dumps({
        "orders": [{"order": n, "poles": [[f, z] for f, z, _ in poles]} for n, poles in orders],
        "seconds_load": loaded - began, "seconds_ssi": done - loaded}))


if __name__ == "__main__":
    main()

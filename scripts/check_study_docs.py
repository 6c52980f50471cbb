#!/usr/bin/env python3
"""Check that docs/study.md, the committed study results and the current code agree.

Two checks, both failing with a message that names where and both values:

1. docs/study.md against the committed files in docs/results/ (cheap, exact at the doc's
   printed precision). Every table of study results and every number in the prose that is
   derived from them (slopes, geometric-mean ratios and their spreads, percentages, converged
   counts, sizes) is recomputed from the committed mse.csv / trends.csv and compared with the
   doc's text, rounded to as many decimals as the doc prints. The systems, noise and PID of
   "The experiments" are compared with the library's ctid.study_setup. Run times and memory
   are measurements of the run the doc names and are not checked. trends.csv is also checked
   against the mse.csv beside it, and runs-sample.csv for holding every sampled run.

2. The committed files against the current code. The reduced studies (10 sizes x 50 runs)
   are rerun into a temporary folder and their mse.csv / trends.csv compared with the
   committed ones; of the paper-size studies, the runs in runs-sample.csv (run 0 and 1 at every
   size index, every estimator) are replayed one by one with --size-index j --run-index r.
   --full reruns the paper-size studies entirely and compares everything (10-15 min each).

Tolerances (check 2): integers and text exactly; an estimate or standard error may move by
RTOL = 1e-6 of its size. The estimators stop at a relative parameter change of 1e-10 (open
loop) or 1e-7 (closed loop), so an estimate is only defined to about that precision: 1e-6
leaves a factor 10 over the looser tolerance and is still 3-4 orders of magnitude below the
standard errors (1e-3-1e-2 of the parameters), i.e. far below anything the doc quotes
(measured: from the estimators of 252d8c2 to those of 3080eff, decision 0020 included, the
reduced studies' mse.csv moved by at most 0.27 of the tolerances below). The
mse.csv tolerances follow from it: bias moves by at most RTOL |true value|, MSE by at most
2 RTOL |true value| sqrt(MSE) (Cauchy-Schwarz on the mean of 2 e de), predicted MSE (a mean of
squared standard errors) by 2 RTOL of itself. trends.csv is printed with 6 significant digits,
so its values may differ by 1.5 units in the sixth digit plus what the MSE tolerance allows
(slope: a weighted sum of log MSE; ratios: two geometric means of MSE).

--write regenerates the committed files from the current code instead of comparing (only
files in docs/results/<study>/: mse.csv, trends.csv, mse.png, runs-sample.csv);
--use-output STUDY=DIR takes a study's output folder written by the current code instead of
rerunning it.

    /usr/bin/python3 scripts/check_study_docs.py            # 1 and 2 (reduced + samples), 45 s
    /usr/bin/python3 scripts/check_study_docs.py --docs-only
    /usr/bin/python3 scripts/check_study_docs.py --full     # also the paper-size reruns
    /usr/bin/python3 scripts/check_study_docs.py --write [--full] [--use-output open-loop-full=DIR]
"""

import argparse
import concurrent.futures
import csv
import math
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "study.md"
RESULTS = ROOT / "docs" / "results"
RTOL = 1e-6
SAMPLE_RUNS = (0, 1)

# Committed study folders: the ctid study kind, the size options, paper size or not.
STUDIES = {
    "open-loop": ("open-loop", ["--sizes", "10", "--runs", "50"], False),
    "closed-loop": ("closed-loop", ["--sizes", "10", "--runs", "50"], False),
    "open-loop-full": ("open-loop", [], True),
    "closed-loop-full": ("closed-loop", [], True),
}


class CheckError(Exception):
    """A list of mismatches, one message each."""

    def __init__(self, messages):
        super().__init__("\n".join(messages))
        self.messages = messages


# --------------------------------------------------------------------------- study files

def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class Study:
    """The committed mse.csv and trends.csv of one study, with the summaries the doc quotes."""

    def __init__(self, folder):
        self.folder = pathlib.Path(folder)
        self.mse_rows = read_csv(self.folder / "mse.csv")
        self.trend_rows = read_csv(self.folder / "trends.csv")
        self.estimators = list(dict.fromkeys(r["estimator"] for r in self.mse_rows))
        self.parameters = list(dict.fromkeys(r["parameter"] for r in self.mse_rows))

    def column(self, estimator, parameter, name):
        """mse.csv's column `name` over the sizes, in size order."""
        rows = [r for r in self.mse_rows
                if r["estimator"] == estimator and r["parameter"] == parameter]
        rows.sort(key=lambda r: int(r["size_index"]))
        return np.array([float(r[name]) for r in rows])

    def sizes(self):
        return self.column(self.estimators[0], self.parameters[0], "N").astype(int)

    def trend(self, estimator, parameter, name):
        for r in self.trend_rows:
            if r["estimator"] == estimator and r["parameter"] == parameter:
                return float(r[name])
        raise KeyError((estimator, parameter))

    def true_value(self, parameter):
        return self.column(self.estimators[0], parameter, "true_value")[0]

    def log_ratios(self, a, b, parameter, name="mse"):
        return np.log(self.column(a, parameter, name) / self.column(b, parameter, name))

    def ratio(self, a, b, parameter, name="mse"):
        """Geometric mean over the sizes of a's MSE (or predicted MSE) over b's."""
        return float(np.exp(self.log_ratios(a, b, parameter, name).mean()))

    def over_prediction(self, estimator, parameter):
        """Geometric mean over the sizes of MSE / predicted MSE."""
        return float(np.exp(np.mean(np.log(self.column(estimator, parameter, "mse")
                                           / self.column(estimator, parameter, "predicted_mse")))))

    def spread(self, a, b, parameter):
        """The doc's ×/÷ uncertainty of ratio(): exp(standard error of the mean log ratio)."""
        logs = self.log_ratios(a, b, parameter)
        return float(np.exp(logs.std(ddof=1) / math.sqrt(len(logs))))

    def slope(self, estimator, parameter, min_samples=0):
        """Least-squares slope of log MSE against log N (over N >= min_samples)."""
        n = self.sizes()
        keep = n >= min_samples
        mse = self.column(estimator, parameter, "mse")
        return float(np.polyfit(np.log(n[keep]), np.log(mse[keep]), 1)[0])

    def runs(self, estimator):
        return int(self.column(estimator, self.parameters[0], "valid_runs").sum())

    def converged(self, estimator):
        return int(self.column(estimator, self.parameters[0], "converged_runs").sum())

    def runs_per_size(self):
        return int(self.column(self.estimators[0], self.parameters[0], "valid_runs")[0])

    def all_trends(self, name, estimators=None, parameters=None):
        return [self.trend(e, p, name) for e in (estimators or self.estimators)
                for p in (parameters or self.parameters)]


class Setup:
    """The study definition of the library (ctid.study_setup): systems, noise, controller."""

    def __init__(self, kind):
        import ctid  # only check 1 needs the Python package
        self.setup = ctid.study_setup(getattr(ctid.StudyKind, kind.replace("-", "_")))

    def poles(self):
        """Real and imaginary part of each mode's upper pole, in mode order."""
        out = []
        for mode in self.setup.system.submodels:
            pole = max(mode.to_transfer_function().poles(), key=lambda z: z.imag)
            out += [pole.real, pole.imag]
        return out

    def noise_filter(self):
        """c, d of the noise filter (q + c)/(q - d)."""
        return [self.setup.noise_filter.numerator.coefficients[0],
                -self.setup.noise_filter.denominator.coefficients[0]]

    def pid(self):
        """kp, ki, kd of kp + ki q/(q-1) + kd (q-1)/q, then c2, -c1, c0 of its numerator
        c2 q² + c1 q + c0 over q² - q."""
        c0, c1, c2 = self.setup.controller.numerator.coefficients
        kd, kp = c0, -c1 - 2 * c0
        return [kp, c2 - kp - kd, kd, c2, -c1, c0]


def load_studies(results=RESULTS):
    studies = {name: Study(pathlib.Path(results) / name) for name in STUDIES}
    studies.update({f"{kind}-setup": Setup(kind) for kind in ("open-loop", "closed-loop")})
    return studies


def check_trends_file(study, name):
    """trends.csv against the same quantities recomputed from mse.csv."""
    errors = []
    for e in study.estimators:
        for p in study.parameters:
            derived = {"slope": study.slope(e, p),
                       "mse_over_prediction": study.over_prediction(e, p),
                       "mse_over_srivc": study.ratio(e, "srivc", p)}
            for column, value in derived.items():
                printed = study.trend(e, p, column)
                if not printed_close(printed, value):
                    errors.append(f"{name}/trends.csv {e} {p} {column}: file {printed}, "
                                  f"recomputed from mse.csv {value:.6g}")
    return errors


def check_sample_file(study, name):
    """runs-sample.csv holds the runs SAMPLE_RUNS at every size index, for every estimator."""
    wanted = {(e, str(j), str(r)) for e in study.estimators
              for j in range(len(study.sizes())) for r in SAMPLE_RUNS}
    held = [tuple(row[k] for k in RUNS_KEYS)
            for row in read_csv(study.folder / "runs-sample.csv")]
    if sorted(held) != sorted(wanted):
        missing = sorted(wanted - set(held))[:3]
        return [f"{name}/runs-sample.csv: {len(held)} rows, not one per estimator, size index "
                f"and run {SAMPLE_RUNS} ({len(wanted)}); missing e.g. {missing}"]
    return []


def printed_close(printed, value):
    """True if `printed` (6 significant digits) and `value` differ by <= 1.5 units of its
    last digit."""
    return abs(printed - value) <= print_unit(printed)


# --------------------------------------------------------------------------- doc numbers

NUMBER = r"[−-]?\d+(?:[  ]\d{3})*(?:\.\d+)?"


def parse_number(text):
    """The doc's number text -> (value, decimals printed)."""
    clean = text.replace("−", "-").replace(" ", "").replace(" ", "")
    decimals = len(clean.split(".")[1]) if "." in clean else 0
    return float(clean), decimals


def formatted(value, decimals):
    text = f"{value:.{decimals}f}"
    return "0" + text[2:] if text.startswith("-0") and float(text) == 0 else text


def differs(doc_text, value):
    """None if the doc's number equals `value` at the doc's precision, else the value printed
    at that precision."""
    doc_value, decimals = parse_number(doc_text)
    mine = formatted(value, decimals)
    return None if mine == formatted(doc_value, decimals) else mine


def pct(x):
    """A ratio as the percentage it differs from 1 (either way: "within x %")."""
    return 100.0 * abs(1.0 - x)


def lower(x):
    """A ratio below 1 as the percentage it is lower ("x % lower"; negative if higher)."""
    return 100.0 * (1.0 - x)


def sections(text):
    """Heading line -> (first line number, section text) for every '#' heading."""
    lines = text.split("\n")
    starts = [i for i, line in enumerate(lines) if line.startswith("#")]
    out = {}
    for k, start in enumerate(starts):
        end = starts[k + 1] if k + 1 < len(starts) else len(lines)
        out[lines[start].strip()] = (start + 1, "\n".join(lines[start:end]))
    return out


def find_section(secs, prefix):
    for heading, value in secs.items():
        if heading.startswith(prefix):
            return value
    raise CheckError([f"docs/study.md: no section starting with {prefix!r}"])


# Prose claims: (section heading prefix, study, phrase with {} for each number, values).
# In the phrase a space matches any white space (line breaks included); a tuple of values
# for one number ("about 1.3") means every one of them must print as the doc's number.
def _prose_claims():
    add_ol, add_cl = "additive_srivc", "additive_clsrivc"
    return [
        ("## The experiments", "open-loop-full", "DC gains [{}, {}, {}, {}]",
         lambda s: [s.true_value(p) for p in ("b10", "b20", "b30", "b40")]),
        ("## The experiments", "closed-loop-full",
         "Eq. (46), {}/({}p² + {}p + 1) + {}/({}p² + {}p + 1)",
         lambda s: [s.true_value(p) for p in ("b10", "a12", "a11", "b20", "a22", "a21")]),
        ("## The experiments", "open-loop-setup", "poles {}±{}i, {}±{}i, {}±{}i, {}±{}i",
         lambda s: s.poles()),
        ("## The experiments", "open-loop-setup",
         "h = {} s; noise v = (q+{})/(q−{}) e, var e = {}",
         lambda s: [s.setup.sample_time, *s.noise_filter(), s.setup.noise_variance]),
        ("## The experiments", "open-loop-full",
         "(`colored_noise`); {} log-spaced N from {} to {}, {} runs each",
         lambda s: [len(s.sizes()), s.sizes()[0], s.sizes()[-1], s.runs_per_size()]),
        ("## The experiments", "closed-loop-setup",
         "PID C_d(q) = {} + {} q/(q−1) + {} (q−1)/q, i.e. ({} q² − {} q + {})/(q² − q)",
         lambda s: s.pid()),
        ("## The experiments", "closed-loop-setup", "output noise white of variance {};",
         lambda s: [s.setup.noise_variance]),
        ("## The experiments", "closed-loop-full", "{} log-spaced N from {} to {}, {} runs;",
         lambda s: [len(s.sizes()), s.sizes()[0], s.sizes()[-1], s.runs_per_size()]),
        ("## Section 6.1", "open-loop-full", "{} sizes log-spaced from {} to {}, {} runs each",
         lambda s: [len(s.sizes()), s.sizes()[0], s.sizes()[-1], s.runs_per_size()]),
        ("## Section 6.1", "open-loop-full", "the rows of `runs.csv` for runs {} and {} at every",
         lambda s: list(SAMPLE_RUNS)),
        ("## Section 6.1", "open-loop-full", "additive estimator, {} estimates each",
         lambda s: [s.runs("srivc")]),
        ("## Section 6.1", "open-loop-full", "geometric means over the {} sizes",
         lambda s: [len(s.sizes())]),
        ("## Section 6.1", "open-loop-full", "b20 and b30 (by {} % and {} %)",
         lambda s: [lower(s.ratio(add_ol, "srivc", p)) for p in ("b20", "b30")]),
        ("## Section 6.1", "open-loop-full", "The gain is a factor of about {}–{}",
         lambda s: [1 / s.ratio(add_ol, "srivc", "b30"), 1 / s.ratio(add_ol, "srivc", "b20")]),
        ("## Section 6.1", "open-loop-full", "reported covariance within {}–{} %",
         lambda s: [min(map(pct, s.all_trends("mse_over_prediction"))),
                    max(map(pct, s.all_trends("mse_over_prediction")))]),
        ("## Section 6.1", "open-loop-full", "{}/{} SRIVC and {}/{} additive runs converged",
         lambda s: [s.converged("srivc"), s.runs("srivc"), s.converged(add_ol),
                    s.runs(add_ol)]),
        ("## Section 6.2", "closed-loop-full", "{} sizes log-spaced from {} to {}, {} runs each",
         lambda s: [len(s.sizes()), s.sizes()[0], s.sizes()[-1], s.runs_per_size()]),
        ("## Section 6.2", "closed-loop-full", "closed-loop estimator ({} estimates each)",
         lambda s: [s.runs("srivc")]),
        ("## Section 6.2", "closed-loop-full", "geometric means over the {} sizes",
         lambda s: [len(s.sizes())]),
        ("## Section 6.2", "closed-loop-full", "consistent (slopes {} to {})",
         lambda s: [max(s.all_trends("slope")), min(s.all_trends("slope"))]),
        ("## Section 6.2", "closed-loop-full", "a12 (×{}) and a22 (×{})",
         lambda s: [1 / s.ratio(add_cl, "clsrivc", p) for p in ("a12", "a22")]),
        ("## Section 6.2", "closed-loop-full", "equally good here (ratio {}–{})",
         lambda s: [min(s.all_trends("mse_over_srivc", ["clsrivc"])),
                    max(s.all_trends("mse_over_srivc", ["clsrivc"]))]),
        ("## Section 6.2", "closed-loop-full", "reported covariance within {} %",
         lambda s: [max(map(pct, s.all_trends("mse_over_prediction")))]),
        ("## Section 6.2", "closed-loop-full", "{} / {} / {} of {} runs converged",
         lambda s: [s.converged("srivc"), s.converged("clsrivc"), s.converged(add_cl),
                    s.runs("srivc")]),
        ("## Results (reduced", "open-loop", "reduced size: {} sizes × {} runs",
         lambda s: [len(s.sizes()), s.runs_per_size()]),
        ("## Results (reduced", "open-loop", "open-loop   --sizes {} --runs {}",
         lambda s: [len(s.sizes()), s.runs_per_size()]),
        ("## Results (reduced", "closed-loop", "closed-loop --sizes {} --runs {}",
         lambda s: [len(s.sizes()), s.runs_per_size()]),
        ("## Run time", "open-loop-full", "open-loop   --output study-6.1     # {} sizes x {} runs",
         lambda s: [len(s.sizes()), s.runs_per_size()]),
        ("## Run time", "closed-loop-full",
         "closed-loop --output study-6.2     # {} sizes x {} runs",
         lambda s: [len(s.sizes()), s.runs_per_size()]),
        ("## Results (reduced", "open-loop", "`--sizes {} --runs {}` ({} runs per estimator",
         lambda s: [len(s.sizes()), s.runs_per_size(), s.runs("srivc")]),
        ("## Results (reduced", "open-loop",
         "An MSE from {} runs is known to about ±{} % (√(2/{}), the relative standard deviation "
         "of a mean of {} squared",
         lambda s: [s.runs_per_size(), 100 * math.sqrt(2 / s.runs_per_size())]
         + [s.runs_per_size()] * 2),
        ("## Results (reduced", "open-loop",
         "uncertainty exp(s/√{}), s the standard deviation of the {} per-size log ratios",
         lambda s: [len(s.sizes())] * 2),
        ("## Results (reduced", "open-loop", "geometric means over the {} sizes",
         lambda s: [len(s.sizes())]),
        ("### 6.1, open loop", "open-loop", "(log-log slopes {} to {};",
         lambda s: [max(s.all_trends("slope")), min(s.all_trends("slope"))]),
        ("### 6.1, open loop", "open-loop", "covariance prediction within {} %",
         lambda s: [max(map(pct, s.all_trends("mse_over_prediction")))]),
        ("### 6.1, open loop", "open-loop", "Its MSE is {} % lower for b20 and {} % lower for b30",
         lambda s: [lower(s.ratio(add_ol, "srivc", p)) for p in ("b20", "b30")]),
        ("### 6.1, open loop", "open-loop", "b10 and b40 (ratios {} and {})",
         lambda s: [s.ratio(add_ol, "srivc", p) for p in ("b10", "b40")]),
        ("### 6.1, open loop", "open-loop", "independent information ({} and {})",
         lambda s: [s.ratio(add_ol, "srivc", p, "predicted_mse") for p in ("b20", "b30")]),
        ("### 6.1, open loop", "open-loop", "find a factor of about {} in MSE",
         lambda s: [tuple(1 / s.ratio(add_ol, "srivc", p) for p in ("b20", "b30"))]),
        ("### 6.1, open loop", "open-loop", "Convergence: {}/{} SRIVC and {}/{} additive runs",
         lambda s: [s.converged("srivc"), s.runs("srivc"), s.converged(add_ol),
                    s.runs(add_ol)]),
        ("### 6.2, closed loop", "closed-loop", "All slopes are {} to {}",
         lambda s: [max(s.all_trends("slope")), min(s.all_trends("slope"))]),
        ("### 6.2, closed loop", "closed-loop", "within {} % of its prediction; {}/{} runs",
         lambda s: [max(map(pct, s.all_trends("mse_over_prediction"))),
                    sum(map(s.converged, s.estimators)), sum(map(s.runs, s.estimators))]),
        ("### 6.2, closed loop", "closed-loop", "fitted over N ≥ {} only they are {} to {}",
         lambda s: [3000] + [f(s.slope(e, p, 3000) for e in s.estimators for p in ("a21", "a22"))
                             for f in (max, min)]),
        ("### 6.2, closed loop", "closed-loop",
         "{} % lower for a12 (the slow mode's a_i2), {} % for a22, {} % for b20, {}–{} % for "
         "a11 and a21, {} % for b10",
         lambda s: [lower(s.ratio(add_cl, "clsrivc", p)) for p in ("a12", "a22", "b20")]
         + sorted(lower(s.ratio(add_cl, "clsrivc", p)) for p in ("a11", "a21"))
         + [lower(s.ratio(add_cl, "clsrivc", "b10"))]),
        ("### 6.2, closed loop", "closed-loop", "match the Monte Carlo ones to ±{} %",
         lambda s: [max(pct(s.ratio(add_cl, "clsrivc", p, "predicted_mse")
                            / s.ratio(add_cl, "clsrivc", p)) for p in s.parameters)]),
        ("### 6.2, closed loop", "closed-loop", "(CLSRIVC/SRIVC {}–{})",
         lambda s: [min(s.all_trends("mse_over_srivc", ["clsrivc"])),
                    max(s.all_trends("mse_over_srivc", ["clsrivc"]))]),
    ]


def phrase_regex(phrase):
    parts = [re.escape(p) for p in phrase.split("{}")]
    parts = [re.sub(r"(\\ )+", r"\\s+", p) for p in parts]
    return re.compile(f"({NUMBER})".join(parts))


def line_of(section, offset):
    first_line, text = section
    return first_line + text.count("\n", 0, offset)


def check_prose(secs, studies, covered):
    errors = []
    for heading, name, phrase, values in _prose_claims():
        section = find_section(secs, heading)
        match = phrase_regex(phrase).search(section[1])
        if match is None:
            errors.append(f"docs/study.md section {heading!r}: phrase not found: {phrase!r}")
            continue
        for k, value in enumerate(values(studies[name])):
            line = line_of(section, match.start(k + 1))
            covered.add((line, match.group(k + 1)))
            for one in value if isinstance(value, tuple) else (value,):
                mine = differs(match.group(k + 1), one)
                if mine is not None:
                    errors.append(f"docs/study.md:{line}: {match.group(k + 1)!r} in {phrase!r}, "
                                  f"but {name} gives {mine}")
    return errors


# Tables: (section heading prefix, study, header start, row -> expected values per column).
# A row's first cells name the estimator/parameter; every number in the other cells is
# compared, in order, with the values the column function returns.
def _table_specs():
    add_ol, add_cl = "additive_srivc", "additive_clsrivc"
    estimator_names = {"SRIVC": "srivc", "additive": add_ol}

    def full_61(s, cells):
        e, p = estimator_names[cells[0]], cells[1]
        return [[s.trend(e, p, "slope")], [s.trend(e, p, "mse_over_prediction")],
                [s.trend(e, p, "mse_over_srivc")]]

    def full_62(s, cells):
        p = cells[0]
        return [[s.trend(add_cl, p, "slope")], [s.trend(add_cl, p, "mse_over_prediction")],
                [s.ratio(add_cl, "clsrivc", p)], [s.trend("clsrivc", p, "mse_over_srivc")]]

    def reduced_61(s, cells):
        p = parameter_cell(s, cells[0])
        return [[s.trend("srivc", p, "slope")], [s.trend(add_ol, p, "slope")],
                [s.ratio(add_ol, "srivc", p), s.spread(add_ol, "srivc", p)],
                [s.ratio(add_ol, "srivc", p, "predicted_mse")],
                [s.trend(e, p, "mse_over_prediction") for e in ("srivc", add_ol)]]

    def reduced_62(s, cells):
        p = parameter_cell(s, cells[0])
        return [[s.trend(e, p, "slope") for e in ("srivc", "clsrivc", add_cl)],
                [s.trend("clsrivc", p, "mse_over_srivc")],
                [s.ratio(add_cl, "clsrivc", p), s.spread(add_cl, "clsrivc", p)],
                [s.ratio(add_cl, "clsrivc", p, "predicted_mse")],
                [s.trend(add_cl, p, "mse_over_prediction")]]

    return [
        ("## Section 6.1", "open-loop-full", "| estimator | parameter |", 2, full_61),
        ("## Section 6.2", "closed-loop-full", "| parameter | slope (additive)", 1, full_62),
        ("### 6.1, open loop", "open-loop", "| parameter | slope SRIVC |", 1, reduced_61),
        ("### 6.2, closed loop", "closed-loop", "| parameter | slope SRIVC /", 1, reduced_62),
    ]


def parameter_cell(study, cell):
    """'b20 (0.4)' -> 'b20', checking the true value in brackets against mse.csv."""
    match = re.fullmatch(r"(\w+)\s*\(([\d.]+)\)", cell)
    if match is None:
        raise CheckError([f"table cell {cell!r} is not 'parameter (true value)'"])
    if float(match.group(2)) != study.true_value(match.group(1)):
        raise CheckError([f"table cell {cell!r}: true value in mse.csv is "
                          f"{study.true_value(match.group(1)):g}"])
    return match.group(1)


def table_rows(section, header):
    """(line number, cells) of the data rows of the table whose header starts with `header`."""
    first_line, text = section
    lines = text.split("\n")
    start = next((i for i, line in enumerate(lines) if line.startswith(header)), None)
    if start is None:
        raise CheckError([f"docs/study.md: no table starting {header!r} near line {first_line}"])
    rows = []
    for i in range(start + 2, len(lines)):
        if not lines[i].startswith("|"):
            break
        cells = [c.strip().replace("**", "") for c in lines[i].strip().strip("|").split("|")]
        rows.append((first_line + i, cells))
    return rows


def check_tables(secs, studies, covered):
    errors = []
    for heading, name, header, key_cells, expected in _table_specs():
        study = studies[name]
        rows = table_rows(find_section(secs, heading), header)
        per_parameter = len(study.estimators) if key_cells == 2 else 1  # (estimator, param)
        if len(rows) != len(study.parameters) * per_parameter:
            errors.append(f"docs/study.md:{rows[0][0] if rows else '?'}: table {header!r} has "
                          f"{len(rows)} rows, not one per parameter"
                          + (" and estimator" if key_cells == 2 else ""))
        for line, cells in rows:
            covered.update((line, n) for n in re.findall(NUMBER, " ".join(cells[:key_cells])))
            try:
                columns = expected(study, cells)
            except CheckError as e:
                errors.extend(f"docs/study.md:{line}: {m}" for m in e.messages)
                continue
            for cell, values in zip(cells[key_cells:], columns):
                numbers = re.findall(NUMBER, cell.replace("×/÷", ""))
                if len(numbers) != len(values):
                    errors.append(f"docs/study.md:{line}: cell {cell!r} should hold "
                                  f"{len(values)} numbers")
                    continue
                for text, value in zip(numbers, values):
                    covered.add((line, text))
                    mine = differs(text, value)
                    if mine is not None:
                        errors.append(f"docs/study.md:{line}: {' '.join(cells[:key_cells])}: "
                                      f"{text!r}, but {name} gives {mine}")
    return errors


def check_docs(doc=DOC, results=RESULTS, covered=None):
    """Check 1; returns the list of mismatches (empty if the doc agrees). The (line, number
    text) pairs it compared are added to `covered`."""
    covered = set() if covered is None else covered
    studies = load_studies(results)
    secs = sections(pathlib.Path(doc).read_text())
    errors = []
    for name, (_, _, paper_size) in STUDIES.items():
        errors += check_trends_file(studies[name], name)
        if paper_size:
            errors += check_sample_file(studies[name], name)
    for check in (check_tables, check_prose):
        try:
            errors += check(secs, studies, covered)
        except CheckError as e:
            errors += e.messages
    return errors


def unchecked_numbers(doc=DOC, results=RESULTS):
    """(line, text) of the numbers in docs/study.md that check 1 does not compare."""
    covered = set()
    check_docs(doc, results, covered)
    lines = pathlib.Path(doc).read_text().split("\n")
    return [(i + 1, n) for i, line in enumerate(lines) for n in re.findall(NUMBER, line)
            if (i + 1, n) not in covered]


# --------------------------------------------------------------------------- reruns

MSE_KEYS = ("estimator", "size_index", "parameter")
TRENDS_KEYS = ("estimator", "parameter")
RUNS_KEYS = ("estimator", "size_index", "run_index")
RUNS_EXACT = ("estimator", "size_index", "run_index", "N", "seed", "termination",
              "iterations", "valid", "error")


def mse_tolerance(column, row):
    """Allowed |change| of an mse.csv value (None: compare exactly)."""
    true = abs(float(row["true_value"]))
    if column == "bias":
        return RTOL * true
    if column == "mse":
        return 2 * RTOL * true * math.sqrt(float(row["mse"])) * (1 + 1e-9)
    if column == "predicted_mse":
        return 2 * RTOL * abs(float(row["predicted_mse"]))
    return None


def runs_tolerance(column, row):
    """Allowed |change| of a runs.csv value: estimates and standard errors RTOL of their
    size, the rest exactly."""
    return None if column in RUNS_EXACT else RTOL * abs(float(row[column]))


def print_unit(value, digits=6):
    """1.5 units in the last of `digits` significant digits of `value`."""
    return 1.5 * 10.0 ** (math.floor(math.log10(abs(value))) - (digits - 1)) if value else 0.0


def trends_tolerance(study):
    """Allowed |change| of a trends.csv value: its print precision plus what the mse.csv
    tolerances allow (log MSE moves by at most r = max relative MSE tolerance)."""
    def relative(estimator, parameter):
        return max(mse_tolerance("mse", row) / float(row["mse"]) for row in study.mse_rows
                   if row["parameter"] == parameter and row["estimator"] in (estimator, "srivc"))

    log_n = np.log(study.sizes())
    weights = (log_n - log_n.mean()) / ((log_n - log_n.mean()) ** 2).sum()

    def tolerance(column, row):
        if column in TRENDS_KEYS:
            return None
        value, r = float(row[column]), relative(row["estimator"], row["parameter"])
        spread = {"slope": r * np.abs(weights).sum(),  # a weighted sum of log MSE
                  "mse_over_prediction": abs(value) * (r + 2 * RTOL) * 1.01,
                  "mse_over_srivc": abs(value) * 2 * r * 1.01,
                  "n_mse_at_largest_N": abs(value) * r * 1.01}[column]
        return print_unit(value) + spread

    return tolerance


def compare_rows(label, committed, current, keys, tolerance):
    """Mismatches between two CSV row lists: the same rows (by `keys`), and in each column
    the same text, or for floats |difference| <= tolerance(column, committed row)."""
    old = {tuple(r[k] for k in keys): r for r in committed}
    new = {tuple(r[k] for k in keys): r for r in current}
    errors = [f"{label}: row {k} only in the committed file" for k in old if k not in new]
    errors += [f"{label}: row {k} only in the current run" for k in new if k not in old]
    for key in old.keys() & new.keys():
        a, b = old[key], new[key]
        for column in a:
            tol = tolerance(column, a)
            if column not in b:
                errors.append(f"{label}: column {column} missing in the current run")
            elif tol is None:
                if a[column] != b[column]:
                    errors.append(f"{label} {key} {column}: committed {a[column]}, "
                                  f"current {b[column]}")
            elif not float_close(float(a[column]), float(b[column]), tol):
                errors.append(f"{label} {key} {column}: committed {a[column]}, current "
                              f"{b[column]} (|difference| "
                              f"{abs(float(a[column]) - float(b[column])):.3g} > tolerance "
                              f"{tol:.3g})")
    return sorted(errors)


def float_close(x, y, tolerance):
    return abs(x - y) <= tolerance or (math.isnan(x) and math.isnan(y))


def ctid_binary():
    build = pathlib.Path(os.environ.get("CTID_BUILD_DIR", ROOT / "build"))
    return build / "apps" / "ctid" / "ctid"


def run_ctid(ctid, args):
    done = subprocess.run([str(ctid), *args], capture_output=True, text=True)
    if done.returncode != 0:
        raise CheckError([f"{' '.join(map(str, [ctid, *args]))} failed: {done.stderr.strip()}"])


def run_study(ctid, name, folder, threads=2):
    """Rerun the committed study `name` with the current code into `folder`."""
    kind, size_args, _ = STUDIES[name]
    run_ctid(ctid, ["study", kind, *size_args, "--seed", "1", "--threads", str(threads),
                    "--no-plot", "-q", "-o", str(folder)])
    return pathlib.Path(folder)


def replay(ctid, name, size_index, run_index, folder):
    """runs.csv rows of run `run_index` at size `size_index`, replayed alone."""
    kind, size_args, _ = STUDIES[name]
    out = pathlib.Path(folder) / f"{name}-{size_index}-{run_index}"
    run_ctid(ctid, ["study", kind, *size_args, "--seed", "1", "--size-index", str(size_index),
                    "--run-index", str(run_index), "--no-plot", "-q", "-o", str(out)])
    return read_csv(out / "runs.csv")


def sample_rows(runs_rows):
    return [r for r in runs_rows if int(r["run_index"]) in SAMPLE_RUNS]


def replay_sample(ctid, name, results, folder, workers=2):
    """Replay every run of the committed runs-sample.csv; returns the mismatches."""
    committed = read_csv(pathlib.Path(results) / name / "runs-sample.csv")
    cases = sorted({(int(r["size_index"]), int(r["run_index"])) for r in committed})
    with concurrent.futures.ThreadPoolExecutor(workers) as pool:
        replays = pool.map(lambda c: replay(ctid, name, c[0], c[1], folder), cases)
        current = [row for rows in replays for row in rows]
    return compare_rows(f"{name}/runs-sample.csv", committed, current, RUNS_KEYS,
                        runs_tolerance)


def compare_study(name, results, folder):
    """A rerun's mse.csv and trends.csv (and runs-sample.csv for a paper-size study) against
    the committed ones."""
    committed, current = pathlib.Path(results) / name, pathlib.Path(folder)
    errors = compare_rows(f"{name}/mse.csv", read_csv(committed / "mse.csv"),
                          read_csv(current / "mse.csv"), MSE_KEYS, mse_tolerance)
    errors += compare_rows(f"{name}/trends.csv", read_csv(committed / "trends.csv"),
                           read_csv(current / "trends.csv"), TRENDS_KEYS,
                           trends_tolerance(Study(committed)))
    if STUDIES[name][2]:
        errors += compare_rows(f"{name}/runs-sample.csv",
                               read_csv(committed / "runs-sample.csv"),
                               sample_rows(read_csv(current / "runs.csv")), RUNS_KEYS,
                               runs_tolerance)
    return errors


def check_code(ctid, results=RESULTS, full=False, outputs=None):
    """Check 2; returns the list of mismatches."""
    outputs = outputs or {}
    errors = []
    with tempfile.TemporaryDirectory(prefix="ctid-study-check-") as tmp:
        for name, (_, _, paper_size) in STUDIES.items():
            if name in outputs:
                errors += compare_study(name, results, outputs[name])
            elif not paper_size or full:
                errors += compare_study(name, results, run_study(ctid, name, f"{tmp}/{name}"))
            else:
                errors += replay_sample(ctid, name, results, tmp)
    return errors


# --------------------------------------------------------------------------- --write

def write_results(ctid, full=False, outputs=None, results=RESULTS):
    """Regenerate docs/results/<study>/{mse.csv, trends.csv, mse.png, runs-sample.csv} from
    the current code (paper-size studies only with --full or --use-output)."""
    outputs = outputs or {}
    written = []
    with tempfile.TemporaryDirectory(prefix="ctid-study-write-") as tmp:
        for name, (_, _, paper_size) in STUDIES.items():
            if name in outputs:
                source = pathlib.Path(outputs[name])
            elif not paper_size or full:
                source = run_study(ctid, name, f"{tmp}/{name}")
            else:
                continue
            # Everything is made in tmp first, so a failure leaves docs/results untouched.
            staged = pathlib.Path(tmp) / f"{name}-staged"
            staged.mkdir()
            for file in ("mse.csv", "trends.csv"):
                shutil.copyfile(source / file, staged / file)
            if paper_size:
                write_sample(source / "runs.csv", staged / "runs-sample.csv")
            subprocess.run([sys.executable, "-m", "ctid.plot", "mse", str(staged / "mse.csv"),
                            str(staged / "mse.png")], check=True)
            target = pathlib.Path(results) / name
            target.mkdir(parents=True, exist_ok=True)
            for file in staged.iterdir():
                shutil.copyfile(file, target / file.name)
            written.append(name)
    return written


def write_sample(runs_csv, sample_csv):
    with open(runs_csv, newline="") as f:
        reader = csv.DictReader(f)
        rows = [r for r in reader if int(r["run_index"]) in SAMPLE_RUNS]
        fields = reader.fieldnames
    with open(sample_csv, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)


# --------------------------------------------------------------------------- main

def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--docs-only", action="store_true", help="check 1 only")
    parser.add_argument("--full", action="store_true", help="rerun the paper-size studies")
    parser.add_argument("--write", action="store_true",
                        help="regenerate docs/results from the current code")
    parser.add_argument("--use-output", action="append", default=[], metavar="STUDY=DIR",
                        help="a study output folder of the current code instead of a rerun")
    parser.add_argument("--list-unchecked", action="store_true",
                        help="list the numbers of docs/study.md that are not checked")
    parser.add_argument("--ctid", default=None, help="the ctid binary (default: build/)")
    args = parser.parse_args(argv)
    ctid = pathlib.Path(args.ctid) if args.ctid else ctid_binary()
    outputs = dict(item.split("=", 1) for item in args.use_output)
    unknown = set(outputs) - set(STUDIES)
    if unknown:
        parser.error(f"unknown study {sorted(unknown)}; one of {sorted(STUDIES)}")
    if args.list_unchecked:
        for line, text in unchecked_numbers():
            print(f"docs/study.md:{line}: {text}")
        return 0
    if args.write:
        print("wrote", ", ".join(write_results(ctid, args.full, outputs)))
        return 0
    errors = check_docs()
    if not args.docs_only:
        errors += check_code(ctid, full=args.full, outputs=outputs)
    for message in errors:
        print(message, file=sys.stderr)
    print(f"{len(errors)} mismatches" if errors else "docs/study.md and docs/results agree")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())

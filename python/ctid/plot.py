"""Command-line entry point for ctid's figures, used by the C++ CLI's ``--plot`` flag.

    /usr/bin/python3 -m ctid.plot KIND INPUT OUTPUT [--title TEXT] [--frf FRF.json]
                                  [--against RESULT2.json]

KIND is one of bode, modes, frf, frf_matrix, validation, compare, residuals, mse,
stabilisation, mode_shapes, mac, frf_matrix_overlay; INPUT a JSON (bode, modes, frf_matrix: the
mimo_frf document of `ctid frf -o X.json`, stabilisation: the scan `ctid structure -o` writes,
compare: {"t", "y", "window": [start, end], "initial_state", "models": [{"label", "output"}]},
mode_shapes and mac: the mimo_estimation_result of `ctid fit --input-columns ... -o R.json`,
frf_matrix_overlay: that result or a mimo_additive_model, drawn over the mimo_frf document given
by --frf) or CSV (frf, validation, residuals, mse) file in the formats of docs/python.md;
--against gives mac a second estimate for the columns. OUTPUT ends in .png or .svg. Exit status 0
on success, 2 for bad usage or input (one line on stderr), 1 otherwise.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys

import numpy as np

KINDS = ("bode", "modes", "frf", "frf_matrix", "validation", "compare", "residuals", "mse",
         "stabilisation", "mode_shapes", "mac", "frf_matrix_overlay")
MIMO_KINDS = ("mode_shapes", "mac", "frf_matrix_overlay")


class InputError(Exception):
    """Bad input file or arguments (exit status 2)."""


def _polynomial(document, field, where):
    if field not in document:
        raise InputError(f"{where}: missing field '{field}'")
    return [float(c) for c in document[field]]


def model_from_json(document, where="model"):
    """A ctid.TransferFunction or ctid.AdditiveModel from the model JSON of docs/formats.md
    (coefficients under *_ascending, a "type" field)."""
    import ctid

    kind = document.get("type")
    delay = float(document.get("input_delay", 0.0))
    if kind == "transfer_function":
        return ctid.TransferFunction(
            _polynomial(document, "numerator_ascending", where),
            _polynomial(document, "denominator_ascending", where), delay)
    if kind == "additive_model":
        submodels = [
            ctid.Submodel(
                ctid.Polynomial(_polynomial(s, "denominator_ascending", f"{where}.submodels")),
                ctid.Polynomial(_polynomial(s, "numerator_ascending", f"{where}.submodels")),
                int(s.get("integrators", 0)))
            for s in document.get("submodels", [])
        ]
        return ctid.AdditiveModel(submodels, delay)
    raise InputError(f"{where}: 'type' is {kind!r}; expected 'transfer_function' or "
                     "'additive_model'")


def mimo_model_from_json(document, where="model"):
    """A ctid.MimoAdditiveModel from a "mimo_additive_model" document (docs/formats.md:
    "inputs", "outputs", "submodels": [{"denominator_ascending", "numerators_ascending": output
    by output, input by input}], optional "direct": one row per output)."""
    import ctid

    if document.get("type") != "mimo_additive_model":
        raise InputError(f"{where}: 'type' is {document.get('type')!r}; expected "
                         "'mimo_additive_model'")
    for name in ("inputs", "outputs", "submodels"):
        if name not in document:
            raise InputError(f"{where}: missing field '{name}'")
    inputs, outputs = int(document["inputs"]), int(document["outputs"])
    submodels = []
    for k, entry in enumerate(document["submodels"]):
        place = f"{where}.submodels[{k}]"
        numerators = entry.get("numerators_ascending")
        if numerators is None or len(numerators) != inputs * outputs:
            raise InputError(f"{place}: needs {inputs * outputs} numerators_ascending "
                             f"({outputs} outputs x {inputs} inputs)")
        submodels.append(ctid.MimoSubmodel(
            ctid.Polynomial(_polynomial(entry, "denominator_ascending", place)),
            [ctid.Polynomial([float(c) for c in b]) for b in numerators],
            int(entry.get("integrators", 0))))
    direct = np.asarray(document.get("direct", np.zeros((0, 0))), dtype=float)
    delays = np.asarray(document.get("input_delays", []), dtype=float)
    return ctid.MimoAdditiveModel(inputs, outputs, submodels, direct.reshape(
        (outputs, inputs) if direct.size else (0, 0)), delays)


def _read_json(path):
    with open(path, encoding="utf-8") as handle:
        document = json.load(handle)
    if not isinstance(document, dict):
        raise InputError(f"{path}: expected a JSON object")
    return document


def _mimo_result(path):
    """(MimoEstimationResult, output names or None) of a mimo_estimation_result document."""
    import ctid

    document = _read_json(path)
    if document.get("type") != "mimo_estimation_result":
        raise InputError(f"{path}: not a mimo_estimation_result document (type "
                         f"{document.get('type')!r})")
    result = ctid.read_result(path)
    names = document.get("data", {}).get("outputs") if isinstance(
        document.get("data"), dict) else None
    return result, names


def _mimo_figure(kind, path, output, title, frf=None, against=None):
    from . import plotting

    if kind == "frf_matrix_overlay":
        if frf is None:
            raise InputError("frf_matrix_overlay needs --frf FRF.json (a mimo_frf document, "
                             "e.g. from ctid frf -o FRF.json)")
        frf_document = _read_json(frf)
        if frf_document.get("type") != "mimo_frf":
            raise InputError(f"{frf}: not a mimo_frf document")
        document = _read_json(path)
        if document.get("type") == "mimo_additive_model":
            model = mimo_model_from_json(document, path)
        else:
            model, _ = _mimo_result(path)
        return plotting.frf_matrix_overlay(model, frf_document, title=title, filename=output)
    result, names = _mimo_result(path)
    if not result.modes:
        raise InputError(f"{path}: the estimate has no modes (no second-order submodel)")
    if kind == "mode_shapes":
        return plotting.mode_shapes(result, output_names=names, title=title, filename=output)
    second = None
    if against is not None:
        second, other_names = _mimo_result(against)
        if names is not None and other_names is not None and list(names) != list(other_names):
            raise InputError(f"{against}: its outputs ({', '.join(other_names)}) are not those "
                             f"of {path} ({', '.join(names)})")
    return plotting.mac_matrix(result, second, title=title, filename=output)


class _Frf:
    """The fields of ctid.Frf that the plots use, read from JSON or from the CSV of ctid frf."""

    @classmethod
    def from_rows(cls, rows, path):
        frf = cls.__new__(cls)
        frf.frequencies = _column(rows, ("frequency",), path)
        frf.response = _column(rows, ("real",), path) + 1j * _column(rows, ("imag",), path)
        frf.coherence = _column(rows, ("coherence",), path) if "coherence" in rows[0] else []
        frf.variance = _column(rows, ("variance",), path) if "variance" in rows[0] else []
        return frf

    def __init__(self, document):
        try:
            self.frequencies = np.asarray(document["frequencies"], dtype=float)
            self.response = (np.asarray(document["real"], dtype=float)
                             + 1j * np.asarray(document["imag"], dtype=float))
        except KeyError as missing:
            raise InputError(f"frf: missing field {missing}") from None
        if self.frequencies.shape != self.response.shape:
            raise InputError("frf: frequencies, real and imag must have the same length")
        self.variance = np.asarray(document.get("variance", []), dtype=float)


def _read_csv(path):
    with open(path, newline="") as stream:
        rows = list(csv.DictReader(stream))
    if not rows:
        raise InputError(f"{path}: no data rows")
    return rows


def _column(rows, names, path):
    for name in names:
        if name in rows[0]:
            return np.array([float(r[name]) for r in rows])
    raise InputError(f"{path}: needs a column named {' or '.join(names)}")


def _frequency_figure(kind, path, output, title):
    from . import plotting

    with open(path) as stream:
        document = json.load(stream)
    if "type" in document:
        document = {"model": document}
    if "model" not in document:
        raise InputError(f"{path}: needs a 'model' object or a model document")
    model = model_from_json(document["model"], f"{path}: model")
    frf = _Frf(document["frf"]) if "frf" in document else None
    covariance = document.get("covariance")
    omegas = None
    if "frequency_range" in document:
        low, high = document["frequency_range"]
        omegas = np.logspace(np.log10(low), np.log10(high), 400)
    if kind == "bode":
        return plotting.bode(model, frf=frf, covariance=covariance, omegas=omegas,
                             title=title, filename=output)
    return plotting.modes(model, omegas=omegas, frf=frf, title=title, filename=output)


def _compare_figure(path, output, title):
    import ctid
    from . import plotting

    with open(path) as stream:
        document = json.load(stream)
    for name in ("t", "y", "models"):
        if name not in document:
            raise InputError(f"{path}: missing field '{name}'")
    t = np.asarray(document["t"], dtype=float)
    y = np.asarray(document["y"], dtype=float)
    if len(t) < 2 or len(y) != len(t):
        raise InputError(f"{path}: 't' and 'y' need the same length, at least 2")
    h = (t[-1] - t[0]) / (len(t) - 1)
    data = ctid.SampledData(h, np.zeros_like(y), y, start_time=float(t[0]))
    options = ctid.ValidationOptions()
    if "window" in document:
        options.window_start, options.window_end = (float(x) for x in document["window"])
    if document.get("initial_state") == "estimate":
        options.initial_state = ctid.InitialState.estimate
    outputs, labels = [], []
    for i, line in enumerate(document["models"]):
        if "output" not in line or len(line["output"]) != len(t):
            raise InputError(f"{path}: models[{i}] needs an 'output' as long as 't'")
        outputs.append(np.asarray(line["output"], dtype=float))
        labels.append(str(line.get("label", f"model {i + 1}")))
    return plotting.compare(data, outputs, labels=labels, options=options, title=title,
                            filename=output)


def run(kind, path, output, title=None, frf=None, against=None):
    """Draw one figure; returns the Figure. Raises InputError or ValueError on bad input.
    ``frf``: the mimo_frf document frf_matrix_overlay draws under the model; ``against``: a
    second mimo_estimation_result for the columns of mac."""
    import ctid
    from . import plotting

    if kind not in KINDS:
        raise InputError(f"unknown kind '{kind}'; expected one of {', '.join(KINDS)}")
    if not output.lower().endswith((".png", ".svg")):
        raise InputError(f"output '{output}' must end in .png or .svg")
    if frf is not None and kind != "frf_matrix_overlay":
        raise InputError("--frf goes with frf_matrix_overlay")
    if against is not None and kind != "mac":
        raise InputError("--against goes with mac")
    if kind in ("bode", "modes"):
        return _frequency_figure(kind, path, output, title)
    if kind in MIMO_KINDS:
        return _mimo_figure(kind, path, output, title, frf, against)
    if kind == "stabilisation":
        with open(path, encoding="utf-8") as handle:
            document = json.load(handle)
        if not isinstance(document, dict) or "stabilisation" not in document:
            raise InputError(f"{path}: not a structure scan (no 'stabilisation' field)")
        return plotting.stabilisation(document, title=title, filename=output)
    if kind == "compare":
        return _compare_figure(path, output, title)
    if kind == "frf_matrix":
        with open(path, encoding="utf-8") as handle:
            document = json.load(handle)
        if not isinstance(document, dict) or document.get("type") != "mimo_frf":
            raise InputError(f"{path}: not a mimo_frf document")
        return plotting.frf_matrix(document, title=title, filename=output)
    rows = _read_csv(path)
    if kind == "frf":
        return plotting.frf(_Frf.from_rows(rows, path), title=title, filename=output)
    if kind == "validation":
        t = _column(rows, ("t", "time"), path)
        y = _column(rows, ("y",), path)
        simulated = _column(rows, ("y_model", "y_simulated"), path)
        h = (t[-1] - t[0]) / (len(t) - 1)
        data = ctid.SampledData(h, np.zeros_like(y), y, start_time=float(t[0]))
        return plotting.validation(data, simulated, title=title, filename=output)
    if kind == "residuals":
        u = _column(rows, ("u",), path)
        if "residual" in rows[0]:
            residual = _column(rows, ("residual",), path)
        else:
            residual = _column(rows, ("y",), path) - _column(rows, ("y_model",), path)
        return plotting.residual_correlation(residual, u, title=title, filename=output)
    for name in ("estimator", "N", "parameter", "mse"):
        if name not in rows[0]:
            raise InputError(f"{path}: needs a column named {name}")
    return plotting.mse_against_n(rows, title=title, filename=output)


def main(argv=None):
    """Parse the command line, draw the figure, return the exit status."""
    parser = argparse.ArgumentParser(
        prog="python3 -m ctid.plot",
        description="Draw a ctid figure (PNG or SVG) from a JSON or CSV file.")
    parser.add_argument("kind", help="one of: " + ", ".join(KINDS))
    parser.add_argument("input",
                        help="JSON (bode, modes, frf_matrix, compare, stabilisation, mode_shapes, "
                        "mac, frf_matrix_overlay) or CSV (frf, validation, residuals, mse)")
    parser.add_argument("output", help="figure file, .png or .svg")
    parser.add_argument("--title", default=None, help="figure title")
    parser.add_argument("--frf", default=None,
                        help="frf_matrix_overlay: the mimo_frf document (JSON) under the model")
    parser.add_argument("--against", default=None,
                        help="mac: a second mimo_estimation_result for the columns")
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:
        return 2 if exit_.code else 0
    try:
        run(args.kind, args.input, args.output, args.title, args.frf, args.against)
    except (InputError, ValueError, TypeError, OSError, json.JSONDecodeError) as error:
        print(f"ctid.plot: {error}", file=sys.stderr)
        return 2
    except Exception as error:  # noqa: BLE001 - one line, exit status 1
        print(f"ctid.plot: {type(error).__name__}: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Command-line entry point for ctid's figures, used by the C++ CLI's ``--plot`` flag.

    /usr/bin/python3 -m ctid.plot KIND INPUT OUTPUT [--title TEXT] [--frf FRF]
                                  [--against RESULT2.json] [--frequency-unit Hz|rad/s]
                                  [--geometry SENSORS.csv [--geometry-lines LINES.csv]]

KIND is one of bode, modes, frf, frf_matrix, validation, compare, residuals, mse,
stabilisation, mode_shapes, mac, frf_matrix_overlay, tracking, oma_stabilisation, oma_shapes,
oma_mac, step, impulse. INPUT is a result document the command line writes (read by ctid.read_result, or as
JSON for tracking; the table below says which kinds draw it) or one of the files of
docs/python.md (the CLI's --plot inputs and CSV tables):

    estimation_result (ctid fit -o), mode_relocation_result,
    input_delay_scan_result          bode, modes (the estimate)
    structure_scan_result (structure) stabilisation; bode (the recommended fit)
    mimo_structure_scan_result (structure --input-columns ... --output-columns ...)
                                      stabilisation
    delayed_feedback_result (feedback) bode (forward and feedback paths)
    frf (ctid frf -o X.json)          frf
    mimo_frf (frf --input-columns)    frf_matrix
    validation_report (validate -o)   residuals
    study_summary (study's summary)   mse
    mimo_estimation_result (fit --input-columns -o), frf_matrix_fit_result (fit-frf -o)
                                      mode_shapes, mac, frf_matrix_overlay (with --frf)
    mode_tracking_result (ctid track -o) tracking (frequency and damping against time)
    mimo_mode_tracking_result (ctid track --output-columns -o)
                                      tracking
    oma_result (ctid oma -o)          oma_stabilisation, oma_shapes, oma_mac
    CSV of ctid step / impulse -o     step, impulse (t, y and, if present, lower, upper)

--frf gives the measured FRF drawn under the model: bode and modes take an frf document or the
CSV of `ctid frf -o X.csv`, frf_matrix_overlay a mimo_frf document, the CSV table of
`ctid frf --input-columns ... -o X.csv` or a universal file. --against gives mac a second
estimate for the columns. --geometry (and --geometry-lines) draws oma_shapes on the sensors'
wireframe (ctid.geometry, decision 0063). Frequency axes are in Hz unless --frequency-unit rad/s. OUTPUT ends in
.png or .svg. Exit status 0 on success, 2 for bad usage or input (one line on stderr), 1
otherwise.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys

import matplotlib
import numpy as np

# The command line draws into files only, with or without a display.
matplotlib.use("Agg")

KINDS = ("bode", "modes", "frf", "frf_matrix", "validation", "compare", "residuals", "mse",
         "stabilisation", "mode_shapes", "mac", "frf_matrix_overlay", "tracking",
         "oma_stabilisation", "oma_shapes", "oma_mac", "step", "impulse")
MIMO_KINDS = ("mode_shapes", "mac", "frf_matrix_overlay")


class InputError(Exception):
    """Bad input file or arguments (exit status 2)."""


def model_from_json(document, where="model"):
    """A ctid.TransferFunction or ctid.AdditiveModel from the model JSON of docs/formats.md
    (coefficients under *_ascending, a "type" field), read by the C++ reader
    (ctid.model_from_json)."""
    import ctid

    model = ctid.model_from_json(document, where)
    if not isinstance(model, (ctid.TransferFunction, ctid.AdditiveModel)):
        raise InputError(f"{where}: 'type' is {document.get('type')!r}; expected "
                         "'transfer_function' or 'additive_model'")
    return model


def mimo_model_from_json(document, where="model"):
    """A ctid.MimoAdditiveModel from a "mimo_additive_model" document (docs/formats.md),
    read by the C++ reader (ctid.model_from_json)."""
    import ctid

    if document.get("type") != "mimo_additive_model":
        raise InputError(f"{where}: 'type' is {document.get('type')!r}; expected "
                         "'mimo_additive_model'")
    return ctid.model_from_json(document, where)


def _read_json(path):
    with open(path, encoding="utf-8") as handle:
        document = json.load(handle)
    if not isinstance(document, dict):
        raise InputError(f"{path}: expected a JSON object")
    return document


# Which kinds draw each result document (the module docstring's table).
DOCUMENT_KINDS = {
    "estimation_result": ("bode", "modes"),
    "mode_relocation_result": ("bode", "modes"),
    "input_delay_scan_result": ("bode", "modes"),
    "structure_scan_result": ("stabilisation", "bode"),
    "mimo_structure_scan_result": ("stabilisation",),
    "delayed_feedback_result": ("bode",),
    "frf": ("frf",),
    "mimo_frf": ("frf_matrix",),
    "validation_report": ("residuals",),
    "study_summary": ("mse",),
    "mimo_estimation_result": MIMO_KINDS,
    "frf_matrix_fit_result": MIMO_KINDS,
    "mode_tracking_result": ("tracking",),
    "mimo_mode_tracking_result": ("tracking",),
    "oma_result": ("oma_stabilisation", "oma_shapes", "oma_mac"),
}


def _result_document(path, kind, document=None):
    """The result of a document the command line wrote, read by ctid.read_result, after
    checking that ``kind`` draws it; None if the file is not a result document."""
    import ctid

    if document is None:
        if not str(path).lower().endswith(".json"):
            return None
        document = _read_json(path)
    name = document.get("type")
    if name not in DOCUMENT_KINDS:
        return None
    if kind not in DOCUMENT_KINDS[name]:
        raise InputError(f"{path}: a {name} document is drawn by "
                         f"{' or '.join(DOCUMENT_KINDS[name])}, not {kind}")
    return ctid.read_result(path)


def _mimo_result(path):
    """(MimoEstimationResult or FrfMatrixFitResult, output names or None) of its document."""
    document = _read_json(path)
    if document.get("type") not in ("mimo_estimation_result", "frf_matrix_fit_result"):
        raise InputError(f"{path}: not a mimo_estimation_result or frf_matrix_fit_result "
                         f"document (type {document.get('type')!r})")
    result = _result_document(path, "mode_shapes", document)
    names = document.get("data", {}).get("outputs") if isinstance(
        document.get("data"), dict) else None
    return result, names


def _mimo_frf(path):
    """A ctid.MimoFrf from a mimo_frf document, the CSV table of ctid frf or a universal file."""
    import ctid

    if str(path).lower().endswith(".json"):
        document = _read_json(path)
        if document.get("type") != "mimo_frf":
            raise InputError(f"{path}: not a mimo_frf document (type {document.get('type')!r})")
        return ctid.read_result(path)
    return ctid.read_mimo_frf(path)


def _mimo_figure(kind, path, output, title, frf=None, against=None, unit="Hz"):
    from . import plotting

    if kind == "frf_matrix_overlay":
        if frf is None:
            raise InputError("frf_matrix_overlay needs --frf FRF.json (a mimo_frf document, "
                             "e.g. from ctid frf -o FRF.json)")
        measured = _mimo_frf(frf)
        document = _read_json(path)
        if document.get("type") == "mimo_additive_model":
            model = mimo_model_from_json(document, path)
        else:
            result, _ = _mimo_result(path)
            model = result.model
        return plotting.frf_matrix_overlay(model, measured, title=title, filename=output,
                                           frequency_unit=unit)
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
        self.coherence = np.asarray(document.get("coherence", []), dtype=float)


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


def _measured_frf(path):
    """The FRF --frf names for bode and modes: an frf document (ctid frf -o X.json) or the CSV
    of ctid frf -o X.csv."""
    import ctid

    if str(path).lower().endswith(".json"):
        document = _read_json(path)
        if document.get("type") != "frf":
            raise InputError(f"{path}: not an frf document (type {document.get('type')!r})")
        return ctid.read_result(path)
    return _Frf.from_rows(_read_csv(path), path)


def _model_of_result(result, path, kind):
    """(model to draw, further (label, model) pairs) of a result read by ctid.read_result."""
    import ctid

    if isinstance(result, ctid.ModeRelocationResult):
        result = result.estimate
    elif isinstance(result, ctid.InputDelayScanResult):
        result = result.best
    if isinstance(result, ctid.EstimationResult):
        return result, []
    if isinstance(result, ctid.StructureScanResult):
        if not 0 <= result.recommended < len(result.fits):
            raise InputError(f"{path}: the scan recommends no fit (none was usable)")
        return result.fits[result.recommended].transfer_function, []
    if isinstance(result, ctid.DelayedFeedbackResult):
        loop = result.identification.loop
        if not np.any(np.asarray(loop.forward.numerator.coefficients)):
            raise InputError(f"{path}: the identification found no loop to draw "
                             f"({result.identification.message})")
        return loop.forward, [("feedback H", loop.feedback)]
    raise InputError(f"{path}: holds no model that {kind} draws")


def _frequency_figure(kind, path, output, title, frf_path=None, unit="Hz"):
    from . import plotting

    document = _read_json(path)
    frf = _measured_frf(frf_path) if frf_path is not None else None
    result = _result_document(path, kind, document)
    if result is not None:
        model, more = _model_of_result(result, path, kind)
        if kind == "bode":
            return plotting.bode(model, frf=frf, more=more, title=title, filename=output,
                                 frequency_unit=unit)
        return plotting.modes(model, frf=frf, title=title, filename=output, frequency_unit=unit)
    if "type" in document:
        document = {"model": document}
    if "model" not in document:
        raise InputError(f"{path}: needs a 'model' object, a model document or a result "
                         f"document ({', '.join(sorted(DOCUMENT_KINDS))})")
    model = model_from_json(document["model"], f"{path}: model")
    if frf is None and "frf" in document:
        frf = _Frf(document["frf"])
    covariance = document.get("covariance")
    omegas = None
    if "frequency_range" in document:
        # Widened to every resonance of the model, which must not fall off the axis.
        low, high = plotting._cover(*(float(v) for v in document["frequency_range"]), model)
        omegas = np.logspace(np.log10(low), np.log10(high), 400)
    if kind == "bode":
        return plotting.bode(model, frf=frf, covariance=covariance, omegas=omegas,
                             title=title, filename=output, frequency_unit=unit)
    return plotting.modes(model, omegas=omegas, frf=frf, title=title, filename=output,
                          frequency_unit=unit)


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


def _tracking_figure(path, output, title, unit):
    """The tracking figure of a mode_tracking_result document (ctid track -o), read as JSON
    (the command line writes it; no C++ reader is needed to draw it)."""
    from . import plotting

    if not str(path).lower().endswith(".json"):
        raise InputError(f"{path}: tracking draws a mode_tracking_result document "
                         "(ctid track -o)")
    document = _read_json(path)
    if document.get("type") not in ("mode_tracking_result", "mimo_mode_tracking_result"):
        raise InputError(f"{path}: not a mode_tracking_result document "
                         f"(type {document.get('type')!r})")
    for name in ("windows", "tracks"):
        if not isinstance(document.get(name), list):
            raise InputError(f"{path}: missing field '{name}'")
    if not document["windows"]:
        raise InputError(f"{path}: the tracking has no windows")
    return plotting.mode_tracking(document, title=title, filename=output, frequency_unit=unit)


def _response_figure(kind, path, output, title):
    """The response in the CSV of ctid step / impulse -o (t, y[, y_std, lower, upper])."""
    from . import plotting

    rows = _read_csv(path)
    t = _column(rows, ("t",), path)
    y = _column(rows, ("y",), path)
    band = "lower" in rows[0] and "upper" in rows[0]
    lower = _column(rows, ("lower",), path) if band else None
    upper = _column(rows, ("upper",), path) if band else None
    return plotting.response_curve(t, y, lower, upper, kind=kind, title=title, filename=output)


def run(kind, path, output, title=None, frf=None, against=None, frequency_unit="Hz",
        geometry=None, geometry_lines=None):
    """Draw one figure; returns the Figure. Raises InputError or ValueError on bad input.
    ``frf``: the measured FRF drawn under the model (bode, modes: an frf document or CSV;
    frf_matrix_overlay: a mimo_frf document, CSV table or universal file); ``against``: a
    second MIMO estimate for the columns of mac; ``frequency_unit``: "Hz" or "rad/s";
    ``geometry``, ``geometry_lines``: oma_shapes on the sensors' wireframe (ctid.geometry)."""
    import ctid
    from . import plotting

    if kind not in KINDS:
        raise InputError(f"unknown kind '{kind}'; expected one of {', '.join(KINDS)}")
    if not output.lower().endswith((".png", ".svg")):
        raise InputError(f"output '{output}' must end in .png or .svg")
    if frequency_unit not in ("Hz", "rad/s"):
        raise InputError(f"--frequency-unit is '{frequency_unit}'; expected Hz or rad/s")
    if frf is not None and kind not in ("bode", "modes", "frf_matrix_overlay"):
        raise InputError("--frf goes with bode, modes and frf_matrix_overlay")
    if against is not None and kind != "mac":
        raise InputError("--against goes with mac")
    if (geometry is not None or geometry_lines is not None) and kind != "oma_shapes":
        raise InputError("--geometry and --geometry-lines go with oma_shapes")
    if geometry_lines is not None and geometry is None:
        raise InputError("--geometry-lines needs --geometry (the sensors file)")
    unit = frequency_unit
    if kind == "tracking":
        return _tracking_figure(path, output, title, unit)
    if kind in ("step", "impulse"):
        return _response_figure(kind, path, output, title)
    if kind in ("bode", "modes"):
        return _frequency_figure(kind, path, output, title, frf, unit)
    if kind in MIMO_KINDS:
        return _mimo_figure(kind, path, output, title, frf, against, unit)
    result = _result_document(path, kind)
    if kind == "stabilisation":
        if result is None:
            document = _read_json(path)
            if "stabilisation" not in document:
                raise InputError(f"{path}: not a structure scan (no 'stabilisation' field)")
            result = document
        return plotting.stabilisation(result, title=title, filename=output, frequency_unit=unit)
    if kind == "oma_stabilisation":
        return plotting.oma_stabilisation(result, title=title, filename=output,
                                          frequency_unit=unit)
    if kind in ("oma_shapes", "oma_mac"):
        if result is None or not hasattr(result, "channels"):
            raise InputError(f"{path}: {kind} draws an oma_result document")
        if not result.modes:
            raise InputError(f"{path}: the analysis found no mode")
        if kind == "oma_shapes":
            if geometry is not None:
                from .geometry import read_geometry
                geometry = read_geometry(geometry, geometry_lines)
            return plotting.oma_mode_shapes(result, geometry=geometry, title=title,
                                            filename=output)
        return plotting.oma_mac(result, title=title, filename=output)
    if kind == "compare":
        return _compare_figure(path, output, title)
    if kind == "frf_matrix":
        if result is None:
            raise InputError(f"{path}: not a mimo_frf document")
        return plotting.frf_matrix(result, title=title, filename=output, frequency_unit=unit)
    if result is not None:  # frf, residuals, mse from their documents
        if kind == "frf":
            return plotting.frf(result, title=title, filename=output, frequency_unit=unit)
        if kind == "residuals":
            return plotting.residual_correlation(result, title=title, filename=output)
        return plotting.mse_against_n(result, title=title, filename=output)
    if str(path).lower().endswith(".json"):
        raise InputError(f"{path}: {kind} draws a CSV file or a result document "
                         f"({', '.join(n for n, k in DOCUMENT_KINDS.items() if kind in k)})")
    rows = _read_csv(path)
    if kind == "frf":
        return plotting.frf(_Frf.from_rows(rows, path), title=title, filename=output,
                            frequency_unit=unit)
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
                        help="a result document the command line writes, or the JSON (bode, "
                        "modes, compare) or CSV (frf, validation, residuals, mse) of "
                        "docs/python.md")
    parser.add_argument("output", help="figure file, .png or .svg")
    parser.add_argument("--title", default=None, help="figure title")
    parser.add_argument("--frf", default=None,
                        help="the measured FRF under the model: bode, modes: an frf document "
                        "or the CSV of ctid frf; frf_matrix_overlay: a mimo_frf document, CSV "
                        "table or universal file")
    parser.add_argument("--against", default=None,
                        help="mac: a second mimo_estimation_result for the columns")
    parser.add_argument("--frequency-unit", default="Hz", choices=("Hz", "rad/s"),
                        help="unit of the frequency axes (default Hz)")
    parser.add_argument("--geometry", default=None,
                        help="oma_shapes: sensors CSV (channel,x,y[,z][,dx,dy[,dz]])")
    parser.add_argument("--geometry-lines", default=None,
                        help="oma_shapes: lines CSV (from,to channel names) of the wireframe")
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:
        return 2 if exit_.code else 0
    try:
        run(args.kind, args.input, args.output, args.title, args.frf, args.against,
            args.frequency_unit, args.geometry, args.geometry_lines)
    except (InputError, ValueError, TypeError, OSError, json.JSONDecodeError) as error:
        print(f"ctid.plot: {error}", file=sys.stderr)
        return 2
    except Exception as error:  # noqa: BLE001 - one line, exit status 1
        print(f"ctid.plot: {type(error).__name__}: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

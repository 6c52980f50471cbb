"""One self-contained HTML page from ctid's result documents, for a colleague to read.

    /usr/bin/python3 -m ctid.report RESULT.json [VALIDATION.json] -o fit.html [--force]
                                    [--title TEXT]

``ctid report`` runs this module (apps/ctid/report_command.cc). RESULT is a document of
``ctid fit -o`` (``estimation_result``, one input and one output), ``ctid validate -o``
(``validation_report``) or ``ctid oma -o`` (``oma_result``); VALIDATION, a second
``validation_report``, adds the model's check on other data to a fit. The page holds the
verdict in words, the tables (parameters and modes with their standard errors, the
validation figures), the figures of :mod:`ctid.plotting` embedded as PNG data URIs, and what
the documents record about how they were made (the command line, when the document holds
one, and the data file, samples and preprocessing). It needs nothing beside itself to be
shown: no file, script or network.

An existing output is not replaced without ``--force``. Exit status 0 when the page was
written, 2 for bad usage or input (one line on stderr: a missing file, a document that is
not JSON, or a type the report does not read), 1 otherwise. docs/report.md.
"""

from __future__ import annotations

import argparse
import base64
import datetime
import html
import io
import json
import math
import os
import shlex
import sys
import tempfile

#: The document types the report reads, and what writes them.
DOCUMENT_TYPES = {
    "estimation_result": "ctid fit -o",
    "validation_report": "ctid validate -o",
    "oma_result": "ctid oma -o",
}


class InputError(Exception):
    """Bad input file or arguments (exit status 2)."""


# ---------------------------------------------------------------------------------------------
# Reading


def read_document(path):
    """The JSON object in ``path`` with its "type" checked against DOCUMENT_TYPES."""
    try:
        with open(path, encoding="utf-8") as stream:
            document = json.load(stream)
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, not a result document") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(f"{path}: not a JSON document ({error})") from None
    if not isinstance(document, dict):
        raise InputError(f"{path}: not a result document (expected a JSON object)")
    kind = document.get("type")
    if kind not in DOCUMENT_TYPES:
        known = ", ".join(f"{name} ({writer})" for name, writer in DOCUMENT_TYPES.items())
        what = f"a {kind!r} document" if isinstance(kind, str) else "a document without 'type'"
        raise InputError(f"{path}: {what} is not one ctid report reads; it reads {known}")
    return document


def _parsed(path):
    """The result object of the document (ctid.read_result, the C++ reader), which also
    checks every field."""
    import ctid

    try:
        return ctid.read_result(path)
    except ctid.InvalidArgument as error:
        raise InputError(str(error)) from None


# ---------------------------------------------------------------------------------------------
# Formatting


def _number(value, digits=4):
    """A number as a reader wants it: 4 significant digits, '—' when unknown."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    return f"{value:.{digits}g}"


def _plus_minus(value, error):
    if error is None or (isinstance(error, float) and not math.isfinite(error)):
        return _number(value)
    return f"{_number(value)} ± {_number(error, 2)}"


def _percent(value):
    return "—" if value is None else f"{value:.1f} %"


def _table(header, rows, cls="numbers"):
    """A table of ``rows``; ``header`` None for a table of (name, value) pairs."""
    head = "" if header is None else (
        "<thead><tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in header) +
        "</tr></thead>")
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows)
    return f'<table class="{cls}">{head}<tbody>{body}</tbody></table>'


def _preprocessing_text(p):
    """What was done to the record before the fit, in words, from data.preprocessing."""
    words = []
    first, end = p.get("first_row"), p.get("end_row")
    if first or (end is not None and end >= 0):
        words.append(f"rows {first or 0}:{end if end is not None and end >= 0 else ''}")
    detrend = p.get("detrend")
    if detrend and detrend != "none":
        removed = ", ".join(f"{name} {_number(p[key])}" for name, key in (
            ("input", "input_offset"), ("output", "output_offset"),
            ("reference", "reference_offset")) if p.get(key))
        words.append(f"detrend {detrend}" + (f" (offsets removed: {removed})" if removed else ""))
    if (p.get("decimate") or 1) > 1:
        words.append(f"decimated by {p['decimate']}")
    for key in ("input_scale", "output_scale"):
        if p.get(key) not in (None, 1, 1.0):
            words.append(f"{key.replace('_', ' ')} {_number(p[key])}")
    words.extend(p.get("warnings") or [])
    return "; ".join(words) or "none"


def _polynomial(coefficients, variable="s"):
    """'2 s^2 + 0.5 s + 1' from ascending coefficients."""
    terms = []
    for power in range(len(coefficients) - 1, -1, -1):
        c = coefficients[power]
        if c is None or c == 0:
            continue
        magnitude = abs(c)
        text = "" if magnitude == 1 and power > 0 else _number(magnitude)
        if power >= 1:
            text += (" " if text else "") + variable + (f"^{power}" if power > 1 else "")
        sign = "-" if c < 0 else "+"
        terms.append((sign, text))
    if not terms:
        return "0"
    first_sign, first = terms[0]
    out = ("-" if first_sign == "-" else "") + first
    for sign, text in terms[1:]:
        out += f" {sign} {text}"
    return out


def _figure_uri(figure):
    """The figure as a PNG data URI; the figure is closed."""
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=90)
    plt.close(figure)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _figure_html(uri, caption):
    return (f'<figure><img src="{uri}" alt="{html.escape(caption)}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def _command_text(words):
    return shlex.join(str(w) for w in words)


# ---------------------------------------------------------------------------------------------
# Sections: each returns (verdict sentences, HTML body) for one document.


def _estimation_section(path, document):
    from . import plotting

    result = _parsed(path)
    verdict = document.get("verdict", {})
    usable = bool(verdict.get("usable", False))
    fit = document.get("fit_percent")
    words = []
    if usable:
        words.append("The fitted model is usable: it passed every quality check of the fit "
                     f"(decision 0007), and its simulated output fits the estimation data to "
                     f"{_percent(fit)}.")
    else:
        reasons = " ".join(verdict.get("reasons", [])) or "a quality check failed."
        words.append(f"The fitted model is NOT usable as it is: {reasons}")
        if verdict.get("advice"):
            words.append(f"What to try: {verdict['advice']}")
    acted = verdict.get("active_constraints") or []
    if acted:  # decision 0058: enforced stability, coefficients at a bound
        words.append("Constraints acted on this estimate: " + "; ".join(acted) + ".")
    parts = []
    tf = document.get("transfer_function", {})
    if isinstance(tf, dict) and "numerator_ascending" in tf:
        delay = document.get("input_delay") or 0.0
        factor = f"e^(-{_number(delay)} s) · " if delay else ""
        parts.append(
            '<p class="model">G(s) = ' + html.escape(factor) + "(" +
            html.escape(_polynomial(tf["numerator_ascending"])) + ") / (" +
            html.escape(_polynomial(tf["denominator_ascending"])) + ")</p>")
    names = document.get("parameter_names", [])
    values = document.get("parameters", [])
    errors = document.get("standard_errors") or [None] * len(values)
    rows = []
    for name, value, error in zip(names, values, errors):
        relative = (abs(error / value) * 100.0
                    if error is not None and value not in (None, 0) else None)
        rows.append((name, _number(value), _number(error, 2),
                     "—" if relative is None else f"{relative:.2g} %"))
    parts.append("<h3>Parameters</h3>" +
                 _table(("parameter", "value", "standard error", "relative"), rows))
    modes = document.get("modes", [])
    if modes:
        rows = [(m.get("submodel", i) + 1,
                 _plus_minus(m.get("natural_frequency_hz"),
                             m.get("natural_frequency_hz_standard_error")),
                 _plus_minus(m.get("damping_ratio"), m.get("damping_ratio_standard_error")),
                 _plus_minus(m.get("gain"), m.get("gain_standard_error")))
                for i, m in enumerate(modes)]
        parts.append("<h3>Modes</h3>" + _table(
            ("submodel", "natural frequency [Hz]", "damping ratio", "gain"), rows))
    summary = [
        ("estimator", document.get("estimator", "—")),
        ("loop", document.get("loop", "—")),
        ("iterations", _number(document.get("iterations"))),
        ("stopped", document.get("message", document.get("termination", "—"))),
        ("fit on the estimation data", _percent(fit)),
        ("input delay", _plus_minus(document.get("input_delay"),
                                    document.get("delay_standard_error") or None) + " s"),
        ("noise variance", _number(document.get("noise_variance"))),
    ]
    parts.append("<h3>The iteration</h3>" + _table(None, summary, cls="pairs"))
    noise = document.get("noise_model")
    if isinstance(noise, dict):
        parts.append(_noise_model_html(noise))
    polish = document.get("polish")
    if isinstance(polish, dict):
        parts.append(_polish_html(polish, names))
    warnings = (document.get("data_checks") or {}).get("warnings") or []
    if warnings:
        parts.append("<h3>Data checks</h3><ul>" +
                     "".join(f"<li>{html.escape(w)}</li>" for w in warnings) + "</ul>")
    figures = [_figure_html(_figure_uri(plotting.bode(result)),
                            "Bode diagram of the model with its 95 % confidence band")]
    if modes:
        figures.append(_figure_html(_figure_uri(plotting.modes(result)),
                                    "The model's submodels (modes) and their sum"))
    parts.append('<div class="figures">' + "".join(figures) + "</div>")
    return words, "".join(parts)


def _noise_model_html(noise):
    """RIVC's ARMA noise model D v = C e (decision 0056): each coefficient with its standard
    error, and the innovation variance."""
    ar, ma = list(noise.get("ar") or [1.0]), list(noise.get("ma") or [1.0])
    names = [f"d{i}" for i in range(1, len(ar))] + [f"c{j}" for j in range(1, len(ma))]
    errors = list(noise.get("standard_errors") or []) + [None] * len(names)
    rows = [(name, _number(value), _number(error, 2))
            for name, value, error in zip(names, ar[1:] + ma[1:], errors)]
    rows.append(("innovation variance", _number(noise.get("innovation_variance")), "—"))
    return (f"<h3>Noise model: ARMA({len(ar) - 1}, {len(ma) - 1}), D(q⁻¹) v = C(q⁻¹) e</h3>" +
            _table(("coefficient", "value", "standard error"), rows))


def _polish_html(polish, names):
    """The output-error polish beside the IV estimate (decision 0057): its criterion and fit
    before and after, the polished coefficients with their standard errors, what was held."""
    values = list(polish.get("parameters") or [])
    errors = list(polish.get("standard_errors") or []) + [None] * len(values)
    labels = list(names)
    if len(values) > len(labels) and polish.get("delay_standard_error"):
        labels.append("tau [s]")
    held = set(polish.get("held_parameters") or [])
    rows = [(name + (" (held)" if name in held else ""), _number(value), _number(error, 2))
            for name, value, error in zip(labels, values, errors)]
    summary = [
        ("criterion", polish.get("criterion", "—")),
        ("per sample", f"{_number(polish.get('start_cost'))} → {_number(polish.get('cost'))}"),
        ("fit", f"{_percent(polish.get('start_fit_percent'))} → "
                f"{_percent(polish.get('fit_percent'))}"),
        ("stopped", polish.get("message") or polish.get("termination", "—")),
    ]
    bounds = polish.get("active_bounds") or []
    if bounds:
        summary.append(("at a bound", ", ".join(bounds)))
    if polish.get("stability_constraint_active"):
        summary.append(("stability", "the constraint acted"))
    return ("<h3>Output-error polish</h3>" + _table(None, summary, cls="pairs") +
            _table(("parameter", "polished value", "standard error"), rows))


def _validation_section(path, document):
    from . import plotting

    report = _parsed(path)
    fit = document.get("fit_percent")
    white = bool(report.residual_white)
    uncorrelated = bool(report.residual_uncorrelated_with_input)
    start = "from rest" if document.get("initial_state") == "zero" else \
        "from its least-squares initial state"
    data = document.get("data", {}) if isinstance(document.get("data"), dict) else {}
    words = [
        f"On the validation data{(' (' + data['file'] + ')') if data.get('file') else ''}, "
        f"the model simulated {start} reproduces the measured output with a fit of "
        f"{_percent(fit)} (100 % is exact, 0 % no better than the output's mean).",
        ("The residuals are white" if white else "The residuals are NOT white") +
        f" (largest autocorrelation {_number(document.get('max_residual_autocorrelation'), 2)}"
        f" against the 99 % bound {_number(document.get('whiteness_bound'), 2)})" +
        (" and uncorrelated with the input" if uncorrelated else
         ", and they are correlated with the input: the model misses part of its effect") +
        f" (largest cross-correlation {_number(document.get('max_cross_correlation'), 2)}).",
    ]
    rows = [
        ("fit", _percent(fit)),
        ("fit from rest", _percent(document.get("fit_zero_state"))),
        ("fit from the estimated initial state", _percent(document.get("fit_estimated_state"))),
        ("window", f"{_number(document.get('window_start'))} s to "
                   f"{_number(document.get('window_end'))} s "
                   f"({_number(document.get('window_samples'))} samples)"),
        ("residual mean", _number(document.get("residual_mean"))),
        ("residual standard deviation", _number(document.get("residual_std"))),
        ("largest residual autocorrelation",
         _number(document.get("max_residual_autocorrelation"), 3)),
        ("largest residual-input correlation", _number(document.get("max_cross_correlation"), 3)),
        ("99 % bound", _number(document.get("whiteness_bound"), 3)),
    ]
    prediction = document.get("prediction")
    if isinstance(prediction, dict):
        rows.append((f"{prediction.get('horizon')}-step-ahead prediction fit (noise model)",
                     _percent(prediction.get("fit_percent"))))
    parts = ["<h3>Scores on the validation window</h3>" + _table(None, rows, cls="pairs")]
    if report.max_lag >= 1:
        figure = plotting.residual_correlation(report)
        parts.append('<div class="figures">' + _figure_html(
            _figure_uri(figure), "Residual autocorrelation and residual-input correlation "
            "with the 99 % bound") + "</div>")
    return words, "".join(parts)


def _oma_section(path, document):
    from . import plotting

    result = _parsed(path)
    verdict = document.get("verdict", {})
    modes = document.get("modes", [])
    channels = document.get("channels", [])
    if verdict.get("usable", False):
        words = [f"The output-only analysis ({document.get('method', '—')}) found "
                 f"{len(modes)} mode{'' if len(modes) == 1 else 's'} in "
                 f"{len(channels)} channel{'' if len(channels) == 1 else 's'}."]
    else:
        reasons = " ".join(verdict.get("reasons", [])) or "no mode was found."
        words = [f"The output-only analysis found nothing usable: {reasons}"]
        if verdict.get("advice"):
            words.append(f"What to try: {verdict['advice']}")
    # fdd and efdd pick peaks of the spectrum: no model orders, no Hankel matrix.
    spectral = document.get("method") in ("fdd", "efdd")
    rows = [(i + 1, _plus_minus(m.get("frequency_hz"), m.get("frequency_hz_std")),
             _plus_minus(m.get("damping_ratio"), m.get("damping_ratio_std")),
             _number(m.get("mpc"), 3),
             "—" if spectral else _number(m.get("supporting_orders")))
            for i, m in enumerate(modes)]
    parts = ["<h3>Modes</h3>" + _table(
        ("mode", "natural frequency [Hz]", "damping ratio", "MPC", "supporting orders"), rows)]
    summary = [("method", document.get("method", "—")),
               ("channels", ", ".join(str(c) for c in channels) or "—"),
               ("samples", _number(document.get("samples"))),
               ("sample time", f"{_number(document.get('sample_time'))} s")]
    if not spectral:
        summary.append(("Hankel block rows", _number(document.get("block_rows"))))
    parts.append("<h3>Analysis</h3>" + _table(None, summary, cls="pairs"))
    if result.stabilisation or len(result.first_singular_value):
        caption = ("The first singular value of the output spectral matrix and the modes "
                   "picked on it" if spectral else
                   "Stabilisation diagram: the poles of every order and the modes chosen")
        parts.append('<div class="figures">' + _figure_html(
            _figure_uri(plotting.oma_stabilisation(result)), caption) + "</div>")
    if result.modes:
        parts.append('<div class="figures">' + _figure_html(
            _figure_uri(plotting.oma_mode_shapes(result)),
            "Mode shapes over the channels (real part ± one standard error; the magnitude "
            "signed by the phase)") + _figure_html(
            _figure_uri(plotting.oma_mac(result)),
            "Auto-MAC of the modes: well-separated shapes give the identity") + "</div>")
    return words, "".join(parts)


SECTIONS = {
    "estimation_result": ("Fit", _estimation_section),
    "validation_report": ("Validation", _validation_section),
    "oma_result": ("Output-only modal analysis", _oma_section),
}


def _provenance(path, document):
    """Rows of what the document records about how it was made."""
    rows = [("document", f"{path} ({document['type']}, written by "
                         f"{DOCUMENT_TYPES[document['type']]})")]
    command = document.get("command")
    if isinstance(command, list) and command:
        rows.append(("command", _command_text(command)))
    data = document.get("data")
    if isinstance(data, dict):
        if data.get("file"):
            rows.append(("data file", ", ".join(data["files"]) if data.get("files")
                         else data["file"]))
        if data.get("samples") is not None:
            rows.append(("samples", _number(data["samples"])))
        if data.get("sample_time") is not None:
            rows.append(("sample time", f"{_number(data['sample_time'])} s"))
        if data.get("input_hold"):
            rows.append(("input hold", data["input_hold"]))
        preprocessing = data.get("preprocessing")
        if isinstance(preprocessing, dict):
            rows.append(("preprocessing", _preprocessing_text(preprocessing)))
    if document.get("model_file"):
        rows.append(("model file", document["model_file"]))
    return rows


STYLE = """
body { font-family: sans-serif; max-width: 60em; margin: 2em auto; padding: 0 1em;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.5em; } h2 { font-size: 1.25em; border-bottom: 1px solid #ccc; }
h3 { font-size: 1.05em; }
.verdict { padding: 0.6em 1em; border-left: 0.4em solid; margin: 1em 0; }
.verdict.good { border-color: #2a7d2a; background: #eef7ee; }
.verdict.bad { border-color: #b22222; background: #fbeeee; }
table { border-collapse: collapse; margin: 0.5em 0 1em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; }
table.numbers td { text-align: right; font-variant-numeric: tabular-nums; }
table.numbers td:first-child, table.pairs td:first-child { text-align: left; }
table.pairs td:first-child { font-weight: bold; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #555; }
pre { background: #f4f4f4; padding: 0.5em; overflow-x: auto; white-space: pre-wrap; }
.model { font-family: monospace; }
"""


def _usable(kind, document):
    """Whether the document's verdict is good, for the colour of the verdict box."""
    if kind == "validation_report":
        return bool(document.get("residual_white")) and bool(
            document.get("residual_uncorrelated_with_input"))
    return bool((document.get("verdict") or {}).get("usable", False))


def render(paths, title=None, report_command=None):
    """The HTML page (a str) for the documents at ``paths`` (one or two; the second a
    validation_report). Raises InputError on bad input."""
    import matplotlib

    matplotlib.use("Agg")
    if not 1 <= len(paths) <= 2:
        raise InputError("give one result document and at most one validation_report")
    documents = [read_document(p) for p in paths]
    if len(documents) == 2 and documents[1]["type"] != "validation_report":
        raise InputError(f"{paths[1]}: the second document must be a validation_report "
                         f"(ctid validate -o), not a {documents[1]['type']}")
    if len(documents) == 2 and documents[0]["type"] == "validation_report":
        raise InputError(f"{paths[0]}: with a validation_report second, the first document is "
                         "the fit (estimation_result) or analysis (oma_result) it checks")
    title = title or f"ctid report: {os.path.basename(paths[0])}"
    verdicts, bodies, provenance = [], [], []
    for path, document in zip(paths, documents):
        heading, section = SECTIONS[document["type"]]
        words, body = section(path, document)
        good = _usable(document["type"], document)
        verdicts.append(f'<div class="verdict {"good" if good else "bad"}"><strong>'
                        f"{html.escape(heading)}:</strong> " +
                        " ".join(html.escape(w) for w in words) + "</div>")
        bodies.append(f"<h2>{html.escape(heading)}</h2>{body}")
        provenance.append(_table(None, _provenance(path, document), cls="pairs"))
    made = "<h2>How this was made</h2>" + "".join(provenance)
    if not any(isinstance(d.get("command"), list) for d in documents):
        made += ("<p>The documents do not record the command lines that wrote them; the data "
                 "and settings above are what they record.</p>")
    if report_command:
        made += ("<p>This page:</p><pre>" + html.escape(_command_text(report_command)) +
                 "</pre>")
    import ctid

    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    made += f"<p>ctid {html.escape(ctid.__version__)}, {stamp}.</p>"
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>"
            f"<h1>{html.escape(title)}</h1><h2>Verdict</h2>{''.join(verdicts)}"
            f"{''.join(bodies)}{made}</body></html>\n")


def write(paths, output, force=False, title=None, report_command=None):
    """Renders the page and writes it to ``output`` (through a temporary file in the same
    folder, moved into place). Refuses an existing output without ``force``, and an output
    that is one of the inputs."""
    if not force and os.path.exists(output):
        raise InputError(f"{output}: exists; give --force to replace it")
    for path in paths:
        if os.path.exists(output) and os.path.exists(path) and os.path.samefile(path, output):
            raise InputError(f"{output}: is also an input")
    folder = os.path.dirname(os.path.abspath(output))
    if not os.path.isdir(folder):
        raise InputError(f"{output}: the folder {folder} does not exist")
    page = render(paths, title, report_command)
    handle, temporary = tempfile.mkstemp(prefix=".ctid-report-", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            stream.write(page)
        os.chmod(temporary, 0o644)
        os.replace(temporary, output)
    except BaseException:
        if os.path.exists(temporary):
            os.unlink(temporary)
        raise
    return page


def main(argv=None):
    """Parse the command line, write the page, return the exit status."""
    prog = os.environ.get("CTID_REPORT_PROG", "python3 -m ctid.report")
    parser = argparse.ArgumentParser(
        prog=prog, description="One self-contained HTML page from ctid's result documents.")
    parser.add_argument("documents", nargs="+", metavar="DOCUMENT",
                        help="RESULT.json (ctid fit, validate or oma -o) and optionally "
                        "VALIDATION.json (ctid validate -o)")
    parser.add_argument("-o", "--output", required=True, help="the HTML page to write")
    parser.add_argument("--force", action="store_true", help="replace an existing output")
    parser.add_argument("--title", default=None, help="the page's title")
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:
        return 2 if exit_.code else 0
    words = prog.split() + list(sys.argv[1:] if argv is None else argv)
    try:
        write(args.documents, args.output, args.force, args.title, words)
    except (InputError, OSError) as error:
        print(f"{prog}: error: {error}", file=sys.stderr)
        return 2
    except Exception as error:  # noqa: BLE001 - one line, exit status 1
        print(f"{prog}: error: {type(error).__name__}: {error}", file=sys.stderr)
        return 1
    print(f"{args.output}: report of {', '.join(args.documents)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

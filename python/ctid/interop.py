"""ctid models and results in the rest of the Python ecosystem.

ctid stores polynomial coefficients in ascending powers of s (``[c0, c1, c2]`` is
c0 + c1 s + c2 s^2); SciPy, python-control and MATLAB's ``tf`` take them in descending powers.
These functions convert, so that no system changes silently on the way:

    g = ctid.from_descending([4.0], [1.0, 0.8, 4.0])     # MATLAB tf(4, [1 0.8 4])
    num, den, delay = ctid.to_descending(result)         # result.model as one transfer function
    lti = ctid.to_scipy(result)                          # scipy.signal.TransferFunction
    sys = ctid.to_control(result)                        # control.TransferFunction (if installed)
    table = ctid.to_dataframe(result)                    # parameters ± se as a pandas DataFrame

Neither SciPy's nor python-control's transfer functions hold an input delay: a model with one
is refused unless ``delay="drop"`` is given (docs/decisions/0033).
"""

import html

import numpy as np

__all__ = ["from_descending", "to_descending", "to_scipy", "to_control", "to_dataframe"]


def _coefficients(values, what):
    array = np.asarray(values, dtype=float)
    if array.ndim == 0:
        array = array.reshape(1)
    if array.ndim != 1 or array.size == 0:
        raise ValueError(f"{what}: give a non-empty one-dimensional list of coefficients")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{what}: coefficients must be finite")
    return array


def from_descending(numerator, denominator, input_delay=0.0):
    """The ctid.TransferFunction of coefficients in descending powers of s, as SciPy,
    python-control and MATLAB's ``tf(num, den)`` give them.

    Leading zeros are dropped (``[0, 1, 2]`` is s + 2). ``input_delay`` is in seconds.

    >>> ctid.from_descending([4.0], [1.0, 0.8, 4.0])   # 4 / (s^2 + 0.8 s + 4)
    """
    from . import _ctid

    num = np.trim_zeros(_coefficients(numerator, "from_descending: numerator"), "f")
    den = np.trim_zeros(_coefficients(denominator, "from_descending: denominator"), "f")
    if den.size == 0:
        raise ValueError("from_descending: the denominator is zero")
    if num.size == 0:
        num = np.zeros(1)
    return _ctid.TransferFunction(num[::-1].copy(), den[::-1].copy(), float(input_delay))


def _transfer_function(model, where):
    """One ctid.TransferFunction for a TransferFunction, an AdditiveModel, or a result that
    holds a model (its ``model``)."""
    from . import _ctid

    if isinstance(model, _ctid.TransferFunction):
        return model
    if isinstance(model, _ctid.AdditiveModel):
        return model.to_transfer_function()
    inner = getattr(model, "model", None)
    if isinstance(inner, (_ctid.TransferFunction, _ctid.AdditiveModel)):
        return _transfer_function(inner, where)
    raise TypeError(
        f"{where}: expected a ctid.TransferFunction, a ctid.AdditiveModel or a result with a "
        f"single-input model, got {type(model).__name__}")


def to_descending(model):
    """``(numerator, denominator, input_delay)``: the model as one transfer function with its
    coefficients in descending powers of s (NumPy arrays) and its input delay in seconds.
    ``model``: a TransferFunction, an AdditiveModel (its submodels summed) or a result whose
    ``model`` is one of these."""
    g = _transfer_function(model, "to_descending")
    num = np.asarray(g.numerator.coefficients, dtype=float)[::-1].copy()
    den = np.asarray(g.denominator.coefficients, dtype=float)[::-1].copy()
    return num, den, float(g.input_delay)


def _without_delay(model, delay, where):
    num, den, tau = to_descending(model)
    if delay not in ("refuse", "drop"):
        raise ValueError(f"{where}: delay is {delay!r}; it must be 'refuse' or 'drop'")
    if tau != 0.0 and delay == "refuse":
        raise ValueError(
            f"{where}: the model has an input delay of {tau:g} s, which the target transfer "
            f"function cannot hold; pass delay='drop' to convert the delay-free part (and apply "
            f"the delay yourself, e.g. as a Pade approximation)")
    return num, den


def to_scipy(model, delay="refuse"):
    """The model as ``scipy.signal.TransferFunction`` (continuous time, descending
    coefficients). A model with an input delay raises ValueError unless ``delay="drop"``."""
    from scipy import signal

    num, den = _without_delay(model, delay, "to_scipy")
    return signal.TransferFunction(num, den)


def to_control(model, delay="refuse"):
    """The model as ``control.TransferFunction`` of python-control (optional: not a
    dependency of ctid). A model with an input delay raises ValueError unless
    ``delay="drop"``."""
    num, den = _without_delay(model, delay, "to_control")
    try:
        import control
    except ImportError as error:
        raise ImportError(
            "to_control needs python-control, which is not installed; ctid.to_descending(model) "
            "gives the descending coefficients that control.tf(num, den) takes") from error
    return control.TransferFunction(num, den)


def _table(value):
    """(columns, rows) of what to_dataframe and the notebook views show."""
    from . import _ctid

    if isinstance(value, _ctid.TimeResponse):
        columns = {"t": value.time, "y": value.output}
        if np.size(value.standard_deviation) == np.size(value.time):
            columns.update(y_std=value.standard_deviation, lower=value.lower, upper=value.upper)
        return {k: np.asarray(v, dtype=float) for k, v in columns.items()}
    if isinstance(value, _ctid.EstimationResult):
        theta = np.asarray(value.parameters, dtype=float)
        se = np.asarray(value.standard_errors, dtype=float)
        names = list(_ctid.parameter_names(value.model))
        if len(names) != theta.size:
            names = [f"theta{k}" for k in range(theta.size)]
        if se.size != theta.size:
            se = np.full(theta.size, np.nan)
        return {"parameter": names, "value": theta, "standard_error": se}
    if isinstance(value, _ctid.OmaResult):
        modes = value.modes
        return {
            "frequency_hz": np.array([m.frequency_hz for m in modes], dtype=float),
            "frequency_hz_std": np.array([m.frequency_hz_std for m in modes], dtype=float),
            "damping_ratio": np.array([m.damping_ratio for m in modes], dtype=float),
            "damping_ratio_std": np.array([m.damping_ratio_std for m in modes], dtype=float),
            "mpc": np.array([m.mpc for m in modes], dtype=float),
        }
    raise TypeError(
        f"to_dataframe: expected a TimeResponse, an EstimationResult or an OmaResult, got "
        f"{type(value).__name__}")


def to_dataframe(value):
    """A pandas DataFrame of ``value``: a TimeResponse (t, y and its band), an
    EstimationResult (each parameter, its value and standard error) or an OmaResult (one row a
    mode). Needs pandas (Debian's python3-pandas)."""
    table = _table(value)
    try:
        import pandas
    except ImportError as error:
        raise ImportError("to_dataframe needs pandas, which is not installed") from error
    return pandas.DataFrame(table)


def _html_table(table):
    columns = list(table)
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    rows = []
    for i in range(len(table[columns[0]])):
        cells = []
        for c in columns:
            v = table[c][i]
            cells.append(f"<td>{html.escape(v if isinstance(v, str) else f'{v:.6g}')}</td>")
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"


def result_html(result):
    """The notebook view of a result: its type, verdict (usable or not, the reasons and the
    advice), its one-line report and, for estimation and modal results, the table of
    to_dataframe. The classes' ``_repr_html_``."""
    parts = [f"<div><strong>{html.escape(type(result).__name__)}</strong>"]
    verdict = getattr(result, "verdict", None)
    if verdict is not None:
        usable = bool(verdict.usable)
        word = "usable" if usable else "not usable"
        colour = "#1a7f37" if usable else "#cf222e"
        parts.append(f' <span style="color:{colour}">{word}</span>')
        reasons = list(getattr(verdict, "reasons", []) or [])
        if reasons:
            items = "".join(f"<li>{html.escape(str(r))}</li>" for r in reasons)
            parts.append(f"<ul>{items}</ul>")
        advice = getattr(verdict, "advice", "")
        if advice:
            parts.append(f"<p>{html.escape(str(advice))}</p>")
    report = getattr(result, "brief_report", None)
    if callable(report):
        parts.append(f"<pre>{html.escape(report())}</pre>")
    try:
        parts.append(_html_table(_table(result)))
    except TypeError:
        pass
    parts.append("</div>")
    return "".join(parts)


def _give_results_an_html_view():
    from . import _ctid

    for name in ("EstimationResult", "OmaResult", "MimoEstimationResult", "TimeResponse"):
        klass = getattr(_ctid, name, None)
        if klass is not None:
            klass._repr_html_ = result_html

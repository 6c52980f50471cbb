"""ctid: continuous-time system identification from sampled data.

Everything of the C++ library is re-exported here with the same names (snake_case
functions, CamelCase classes). Arrays are NumPy arrays; polynomial coefficients are in
ascending powers (``[c0, c1, c2]`` is c0 + c1 s + c2 s^2). Options are keyword arguments
(``ctid.srivc(data, order, max_iterations=50)``) or one options object
(``options=ctid.RefinedIvOptions(...)``); unknown keywords raise TypeError. Bad input raises
``ctid.InvalidArgument`` (a ValueError) with the C++ message. Plots live in
:mod:`ctid.plotting` (matplotlib, imported on demand).
"""

from ._ctid import *  # noqa: F401,F403
from ._ctid import InvalidArgument, ComputationError  # noqa: F401

__version__ = "0.1.0"


def options_to_json(options):
    """Every field of an options object as a JSON-ready dict (enumerations by name)."""
    import json

    from . import _ctid

    return json.loads(_ctid._options_to_json_text(options))


def options_from_json(cls_or_name, document):
    """An options object from a dict or JSON text: the class's defaults, overridden by the keys
    given (unknown keys raise ValueError), then validated. ``cls_or_name`` is the class (e.g.
    ``ctid.RefinedIvOptions``) or its name."""
    import json

    from . import _ctid

    name = cls_or_name if isinstance(cls_or_name, str) else cls_or_name.__name__
    text = document if isinstance(document, str) else json.dumps(document, allow_nan=False)
    return _ctid._options_from_json_text(name, text)


def options_classes():
    """Names of the options classes that options_to_json / options_from_json reach."""
    from . import _ctid

    return list(_ctid._options_classes())
def _repr_from_properties(self):
    """Name(attribute=value, ...) over the class's read-only or read/write attributes: the
    repr of the bound classes that do not derive theirs from a field list."""
    names = []
    for klass in reversed(type(self).__mro__):
        for name, value in vars(klass).items():
            if isinstance(value, property) and not name.startswith("_") and name not in names:
                names.append(name)
    shown = []
    for name in names:
        try:
            shown.append(f"{name}={getattr(self, name)!r}")
        except Exception:  # a property that cannot be read in this state is left out
            continue
    return f"{type(self).__name__}({', '.join(shown)})"


def _give_every_class_a_repr():
    from . import _ctid
    for value in vars(_ctid).values():
        if (isinstance(value, type) and not issubclass(value, BaseException)
                and "__repr__" not in value.__dict__ and not hasattr(value, "__members__")):
            value.__repr__ = _repr_from_properties


_give_every_class_a_repr()

from .interop import (  # noqa: E402,F401
    from_descending, to_descending, to_scipy, to_control, to_dataframe)
from .interop import _give_results_an_html_view  # noqa: E402

_give_results_an_html_view()


def _check_real_samples(where, name, value):
    """Refuse complex samples (NumPy would drop their imaginary parts with only a warning) and
    arrays of anything but numbers, naming the argument. Other values pass to the binding."""
    import numpy as np

    if not isinstance(value, (list, tuple, np.ndarray)):
        return
    array = np.asarray(value)
    if np.iscomplexobj(array):
        raise InvalidArgument(f"{where}: {name} has complex values; ctid takes real samples "
                              "(pass .real or .imag explicitly)")
    if array.dtype.kind not in "biuf":
        raise InvalidArgument(f"{where}: {name} must be numbers, not {array.dtype} values")


def _guard_record_constructors():
    """SampledData and MimoData (and SampledData.from_time_stamps) check their arrays first."""
    import functools

    from . import _ctid

    def guarded(function, where, names, method):
        @functools.wraps(function)
        def wrapper(*args, **kwargs):
            given = args[1:] if method else args  # a method's first argument is self
            for name, value in zip(names, given):
                _check_real_samples(where, name, value)
            for name, value in kwargs.items():
                _check_real_samples(where, name, value)
            return function(*args, **kwargs)
        return wrapper

    _ctid.SampledData.__init__ = guarded(
        _ctid.SampledData.__init__, "SampledData",
        ["sample_time", "input", "output", "reference", "start_time"], True)
    _ctid.MimoData.__init__ = guarded(
        _ctid.MimoData.__init__, "MimoData",
        ["sample_time", "inputs", "outputs", "references", "start_time"], True)
    _ctid.SampledData.from_time_stamps = staticmethod(guarded(
        _ctid.SampledData.from_time_stamps, "SampledData.from_time_stamps",
        ["time", "input", "output", "reference"], False))


_guard_record_constructors()

from .distributed import study  # noqa: E402

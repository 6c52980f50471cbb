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

# SPDX-License-Identifier: MIT
"""isokit: implicit composition, composition-operator design and iso-surface tracking.

The C++ library from Python, with NumPy arrays in and out (docs/python.md):

- ``isokit.operators``: operator specs, the 2014 biharmonic generator, controllers, checks.
- ``isokit.fields``: primitives, HRBFs fitted to points, grids, compositions; values and gradients.
- ``isokit.tracker``: the 2014 iso-surface tracker on a NumPy mesh, for isokit or Python fields.
- ``isokit.skinning``: rigs, their implicit skins and bakes, as ``isokit-skin bake``.

Bad input raises ``isokit.InputError`` (a ``ValueError``) with isokit's one-line message.
"""
import sys as _sys

import numpy as _np

from ._isokit import InputError, __version__, get_num_threads, set_num_threads
from ._isokit import fields, tracker
from ._isokit import operators as _operators

_evaluate_arrays = _operators.evaluate


def _evaluate(grid, f1, f2, d):
    """g, dg/df1, dg/df2 of an operator grid (slices, nf, nf) at f1, f2, d.

    The three are broadcast against each other (scalars included); the results have the
    broadcast shape, float32. Arrays that are already float32, C-contiguous and of one shape are
    not copied.
    """
    a, b, c = (_np.asarray(x) for x in (f1, f2, d))
    if not (a.shape == b.shape == c.shape):
        try:
            a, b, c = _np.broadcast_arrays(a, b, c)
        except ValueError as e:
            raise InputError(f"arguments 'f1', 'f2', 'd': shapes {a.shape}, {b.shape}, {c.shape} do not broadcast") from e
        a, b, c = (_np.ascontiguousarray(x) for x in (a, b, c))
    return _evaluate_arrays(grid, a, b, c)


operators = _operators
operators.evaluate_arrays = _evaluate_arrays
operators.evaluate = _evaluate
_sys.modules[__name__ + ".operators"] = operators  # import isokit.operators
_sys.modules[__name__ + ".fields"] = fields
_sys.modules[__name__ + ".tracker"] = tracker
try:  # isokit.skinning: built with the skinning library (ISOKIT_APPS, the default)
    from ._isokit import skinning

    _sys.modules[__name__ + ".skinning"] = skinning
except ImportError:
    pass

__all__ = ["InputError", "__version__", "get_num_threads", "set_num_threads", "operators", "fields", "tracker", "skinning"]

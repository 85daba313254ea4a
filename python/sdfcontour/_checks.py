"""One conversion per kind of argument: every array and option is checked here, in Python, so the
C++ core never sees a string where numbers belong, a NaN coordinate, an index that would wrap or
an option outside its range. Non-numbers raise TypeError; wrong shapes and values, ValueError,
naming the module's own keyword (ArgumentTypeError is both)."""
import numbers

import numpy as np

from . import _sdfcontour

# Larger coordinates overflow the core's exact predicates (its kLargestCoordinate).
LARGEST_COORDINATE = 1e30

_RANGES = _sdfcontour.option_ranges()  # Python keyword -> (lo, hi), the CLI's table


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong type (a string where numbers belong, a complex array, "no" for a
    flag): a TypeError, and a ValueError too, as the module promises for every bad input."""


def numbers_array(name, value):
    """`value` as a numpy array of real numbers (integer or float), else TypeError."""
    try:
        array = np.asarray(value)
    except Exception as error:  # ragged lists and the like
        raise ArgumentTypeError(f"{name} must be an array of numbers ({error})") from None
    if array.dtype.kind not in "fiu":
        raise ArgumentTypeError(f"{name} must be an array of real numbers, got dtype {array.dtype}")
    return array


def points(name, value, columns=3, finite_limit=LARGEST_COORDINATE):
    """An (n, columns) float64 C-contiguous array with every entry finite and at most
    `finite_limit` in size."""
    array = numbers_array(name, value)
    if array.ndim != 2 or array.shape[1] != columns:
        raise ValueError(f"{name} must have shape (n, {columns}), got {array.shape}")
    array = np.ascontiguousarray(array, dtype=np.float64)
    bad = ~(np.abs(array) <= finite_limit)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise ValueError(f"{name} has a NaN, infinite or too large (over {finite_limit:g}) "
                         f"value (row {row})")
    return array


def faces(name, value, vertex_count):
    """An (m, 3) int32 array of indices into `vertex_count` vertices, checked before narrowing
    (an index of 2**32 + 1 is an error, not 1)."""
    array = numbers_array(name, value)
    if array.dtype.kind not in "iu":
        raise ArgumentTypeError(f"{name} must hold whole numbers (vertex indices), got dtype {array.dtype}")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"{name} must have shape (m, 3), got {array.shape}")
    if array.size and (array.min() < 0 or array.max() >= vertex_count):
        raise ValueError(f"{name} indexes a vertex that the {vertex_count} vertices do not have")
    return np.ascontiguousarray(array, dtype=np.int32)


def number(name, value):
    """A real number (int or float, not bool), else TypeError."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ArgumentTypeError(f"{name} must be a number, got {value!r}")
    return value


def in_range(name, value, whole=False):
    """`value` checked against the shared option table's range for keyword `name`."""
    number(name, value)
    if whole and not isinstance(value, (numbers.Integral,)):
        raise ArgumentTypeError(f"{name} must be a whole number, got {value!r}")
    lo, hi = _RANGES[name]
    if not lo <= float(value) <= hi:  # False for NaN too
        raise ValueError(f"{name} must be between {lo:g} and {hi:g}, got {value!r}")
    return int(value) if whole else float(value)


def whole_in(name, value, low, high):
    """A whole number (not bool) from `low` to `high`, else TypeError or ValueError."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ArgumentTypeError(f"{name} must be a whole number, got {value!r}")
    if not low <= value <= high:
        raise ValueError(f"{name} must be from {low} to {high}, got {value}")
    return int(value)


def flag(name, value):
    """True or False only: "no" is not False."""
    if not isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def choice(name, value, choices):
    """One of `choices` (strings)."""
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")
    return value

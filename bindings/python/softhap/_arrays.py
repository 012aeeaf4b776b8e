"""Conversions between Python/numpy values and the contiguous C arrays the C API reads.

Shapes are checked here (a wrong shape is a ValueError); values (finite, in range, positive)
are left to the C library, which reports them as softhap.Error with its status.
"""

from __future__ import annotations

import ctypes
import operator
import os
from typing import Any, Optional, Sequence, Union

import numpy as np
from numpy.typing import ArrayLike

Shape = Sequence[Optional[int]]

INT32_MAX = 2**31 - 1
INT32_MIN = -(2**31)

_DOUBLE_P = ctypes.POINTER(ctypes.c_double)
_INT32_P = ctypes.POINTER(ctypes.c_int32)


def _shape_text(shape: Shape) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"


def _check_shape(array: np.ndarray, shape: Shape, name: str) -> None:
    ok = array.ndim == len(shape) and all(
        want is None or want == got for want, got in zip(shape, array.shape)
    )
    if not ok:
        raise ValueError(
            "%s must have shape %s, got %s" % (name, _shape_text(shape), tuple(array.shape))
        )


def float_array(value: ArrayLike, name: str, shape: Shape) -> np.ndarray:
    """Return value as a C-contiguous float64 array of the given shape (None = any length)."""
    try:
        array = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError("%s must be an array of numbers: %s" % (name, exc)) from None
    _check_shape(array, shape, name)
    return array


def index_array(value: ArrayLike, name: str, shape: Shape) -> np.ndarray:
    """Return value as a C-contiguous int32 array of the given shape (None = any length).

    The values must be integers that fit in int32; whether they are valid indices is for the C
    library to judge.
    """
    array = np.asarray(value)
    if array.size == 0:
        array = array.astype(np.int32)
    elif array.dtype.kind not in "iu":
        raise ValueError("%s must hold integers, got dtype %s" % (name, array.dtype))
    elif array.min() < INT32_MIN or array.max() > INT32_MAX:
        raise ValueError("%s holds values that do not fit in int32" % name)
    array = np.ascontiguousarray(array, dtype=np.int32)
    _check_shape(array, shape, name)
    return array


def index_list(value: ArrayLike, name: str) -> np.ndarray:
    """index_array of a scalar index or a sequence of indices, as a 1-D array."""
    return index_array(np.atleast_1d(np.asarray(value)), name, (None,))


def count(n: Any, name: str) -> int:
    """Return n as an int after checking it is a whole number that fits in the C API's int32
    (ctypes would silently wrap a larger one); the C call judges the range itself."""
    try:
        value = operator.index(n)
    except TypeError:
        as_float = float(n)
        if not as_float.is_integer():
            raise ValueError("%s must be a whole number, got %r" % (name, n)) from None
        value = int(as_float)
    if not INT32_MIN <= value <= INT32_MAX:
        raise ValueError("%s is %d, outside the C API's int32 range" % (name, value))
    return value


def double_ptr(array: np.ndarray) -> Any:
    """Pointer to the first double of a C-contiguous float64 array (keep the array alive)."""
    return array.ctypes.data_as(_DOUBLE_P)


def int32_ptr(array: np.ndarray) -> Any:
    """Pointer to the first int32 of a C-contiguous int32 array (keep the array alive)."""
    return array.ctypes.data_as(_INT32_P)


def path_bytes(path: Union[str, os.PathLike]) -> bytes:
    """Encode a str or os.PathLike file name for a const char* argument."""
    return os.fsencode(path)

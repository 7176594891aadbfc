r"""Single-threaded BLAS for the small dense products of the steady BEM solvers.

Why: one BEM evaluation of a vesicle makes a dozen BLAS/LAPACK calls on matrices of a few
hundred rows (the tension/V least squares, the products of the influence matrices with the
density columns, the wall LU back-substitution), between numba-parallel assembly loops. A
multi-threaded OpenBLAS hands each of them to its worker threads, which then compete with numba's
threads (and any other load) for the cores: measured on 2 shared cores at (ν, λ) = (0.9, 1.0),
the whole steady solve took 5.2 s with 2 BLAS threads and 2.5 s with one, the 352 x 33
least squares 13 ms (median) against 0.23 ms, the 672 x 352 by 352 x 33 product 8 ms against
0.5 ms. At these sizes one thread is as fast as two on a quiet machine.

:func:`single_threaded_blas` sets the calling thread's OpenBLAS thread count to one for the
duration of a ``with`` block and restores it afterwards (``openblas_set_num_threads_local``,
OpenBLAS >= 0.3.27, in every OpenBLAS library the process has loaded: numpy's and scipy's wheels
each bring one). Elsewhere (another BLAS, an older OpenBLAS, a system without ``/proc``) it does
nothing.
"""

from __future__ import annotations

import ctypes
import os
from contextlib import contextmanager
from functools import cache

# the BLAS libraries must be loaded for _setters to find them: numpy's and scipy's each bring one
import numpy.linalg  # noqa: F401
import scipy.linalg  # noqa: F401

__all__ = ["single_threaded_blas"]


@cache
def _setters() -> tuple:
    """``openblas_set_num_threads_local`` of each OpenBLAS library loaded in the process."""
    try:
        with open("/proc/self/maps") as fh:
            paths = {line.split()[-1] for line in fh
                     if "openblas" in os.path.basename(line.split()[-1]).lower()}
    except OSError:
        return ()
    out = []
    for path in sorted(paths):
        try:
            fn = ctypes.CDLL(path).openblas_set_num_threads_local
        except (OSError, AttributeError):
            continue
        fn.argtypes, fn.restype = [ctypes.c_int], ctypes.c_int
        out.append(fn)
    return tuple(out)


@contextmanager
def single_threaded_blas():
    """Run the block with one OpenBLAS thread in the calling thread (module docstring)."""
    setters = _setters()
    previous = [fn(1) for fn in setters]
    try:
        yield
    finally:
        for fn, n in zip(setters, previous):
            fn(n)

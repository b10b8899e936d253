"""BLAS thread limit for the workbench's many small least-squares problems.

Our regressors are tall and skinny (25 000 x 4): multi-threaded OpenBLAS gains nothing on them and,
on a loaded 2-core machine, loses a lot waiting for its threads (measured: greedy diagnosis of EMPS
2.3 s CPU single-threaded vs 6.3 s with the default threads). :func:`single_threaded_blas` sets
the thread count of the OpenBLAS copies numpy and scipy ship (through their exported
``*_set_num_threads`` symbols, as threadpoolctl does) for the duration of a block and restores it.
Without those libraries it does nothing.
"""
from __future__ import annotations

import contextlib
import ctypes
import glob
import os

_LIBS: list | None = None


def _openblas_libs() -> list:
    global _LIBS
    if _LIBS is not None:
        return _LIBS
    _LIBS = []
    import numpy

    site = os.path.dirname(os.path.dirname(numpy.__file__))
    for path in glob.glob(os.path.join(site, "numpy.libs", "libscipy_openblas*.so*")) + \
            glob.glob(os.path.join(site, "scipy.libs", "libscipy_openblas*.so*")):
        try:
            lib = ctypes.CDLL(path, mode=os.RTLD_NOLOAD | os.RTLD_GLOBAL) if hasattr(os, "RTLD_NOLOAD") \
                else ctypes.CDLL(path)
        except OSError:
            continue  # not loaded in this process
        for suffix in ("64_", "_64_", ""):
            get = getattr(lib, f"scipy_openblas_get_num_threads{suffix}", None)
            put = getattr(lib, f"scipy_openblas_set_num_threads{suffix}", None)
            if get is not None and put is not None:
                get.restype = ctypes.c_int
                put.argtypes = [ctypes.c_int]
                _LIBS.append((get, put))
                break
    return _LIBS


@contextlib.contextmanager
def single_threaded_blas(threads: int = 1):
    """Limit OpenBLAS to ``threads`` threads inside the block."""
    import scipy.linalg  # noqa: F401  (load scipy's OpenBLAS before looking for it)

    libs = _openblas_libs()
    old = [get() for get, _ in libs]
    for _, put in libs:
        put(threads)
    try:
        yield
    finally:
        for (_, put), n in zip(libs, old):
            put(n)


def blas_single(fn):
    """Decorator: run ``fn`` under :func:`single_threaded_blas`."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with single_threaded_blas():
            return fn(*args, **kwargs)

    return wrapper

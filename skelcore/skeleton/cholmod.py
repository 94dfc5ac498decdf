"""CHOLMOD's supernodal Cholesky (SuiteSparse) called through ctypes, so that it runs without the GIL.

The library is the one the cvxopt wheel bundles (``cvxopt.libs/libcholmod*``; a system
``libcholmod`` otherwise). cvxopt's own ``cholmod`` module holds the GIL for a whole factorization
(3 s at 256k points), so a cancel could not be answered meanwhile; through ctypes the factorization
runs in a helper thread while the caller polls (:mod:`.solve`). Only CHOLMOD's stable public
structs are laid out here (``cholmod_sparse``, ``cholmod_dense``, the first fields of
``cholmod_factor``); ``cholmod_common`` is an opaque buffer that ``cholmod_l_start`` fills.
64-bit indices (the ``cholmod_l_`` API), default options (AMD ordering, supernodal when it pays).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import os
import threading
from functools import lru_cache

import numpy as np
import scipy.sparse as sp

__all__ = ["Factor", "library"]

_COMMON_BYTES = 1 << 16  # sizeof(cholmod_common) is ~2.7 kB in CHOLMOD 3-5: ample room
_LONG, _REAL, _DOUBLE, _SYS_A = 2, 1, 0, 0


class _Sparse(ctypes.Structure):
    _fields_ = [("nrow", ctypes.c_size_t), ("ncol", ctypes.c_size_t), ("nzmax", ctypes.c_size_t),
                ("p", ctypes.c_void_p), ("i", ctypes.c_void_p), ("nz", ctypes.c_void_p),
                ("x", ctypes.c_void_p), ("z", ctypes.c_void_p), ("stype", ctypes.c_int),
                ("itype", ctypes.c_int), ("xtype", ctypes.c_int), ("dtype", ctypes.c_int),
                ("sorted", ctypes.c_int), ("packed", ctypes.c_int)]


class _Dense(ctypes.Structure):
    _fields_ = [("nrow", ctypes.c_size_t), ("ncol", ctypes.c_size_t), ("nzmax", ctypes.c_size_t),
                ("d", ctypes.c_size_t), ("x", ctypes.c_void_p), ("z", ctypes.c_void_p),
                ("xtype", ctypes.c_int), ("dtype", ctypes.c_int)]


class _FactorHead(ctypes.Structure):  # the first fields of cholmod_factor
    _fields_ = [("n", ctypes.c_size_t), ("minor", ctypes.c_size_t)]


# cholmod_common's leading fields (CHOLMOD 3-5): their defaults after cholmod_l_start, and the offset
# of ``print``; the layout is checked against these before ``print`` is set to 0 (CHOLMOD must not
# write to the process's stdout: the CLI's JSON goes there)
_SIGNATURE = (("d", 1.2, 8), ("d", 40.0, 40), ("i", 1, 48), ("d", 0.8, 80), ("i", 3, 144))  # grow0,
# supernodal_switch, supernodal, zrelax[0], print
_PRINT_OFFSET = 144


def _quiet(common: ctypes.Array) -> None:
    import struct

    raw = common.raw[:256]
    if all(struct.unpack_from(fmt, raw, off)[0] == want for fmt, want, off in _SIGNATURE):
        ctypes.c_int.from_buffer(common, _PRINT_OFFSET).value = 0


def _candidates() -> list[str]:
    out = []
    try:
        import cvxopt

        libs = os.path.join(os.path.dirname(os.path.dirname(cvxopt.__file__)), "cvxopt.libs")
        out += sorted(glob.glob(os.path.join(libs, "libcholmod*.so*")))
        import cvxopt.cholmod  # noqa: F401  (loads the bundled BLAS/AMD the library needs)
    except ImportError:
        pass
    found = ctypes.util.find_library("cholmod")
    if found:
        out.append(found)
    return out


@lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """The CHOLMOD shared library with the ``cholmod_l_`` calls typed, or None when none loads."""
    for path in _candidates():
        try:
            lib = ctypes.CDLL(path)
            fns = [lib.cholmod_l_start, lib.cholmod_l_finish, lib.cholmod_l_analyze, lib.cholmod_l_factorize,
                   lib.cholmod_l_solve, lib.cholmod_l_free_factor, lib.cholmod_l_free_dense]
        except (OSError, AttributeError):
            continue
        for f in fns:
            f.restype = ctypes.c_int
        lib.cholmod_l_analyze.restype = ctypes.c_void_p
        lib.cholmod_l_analyze.argtypes = [ctypes.POINTER(_Sparse), ctypes.c_void_p]
        lib.cholmod_l_factorize.argtypes = [ctypes.POINTER(_Sparse), ctypes.c_void_p, ctypes.c_void_p]
        lib.cholmod_l_solve.restype = ctypes.POINTER(_Dense)
        lib.cholmod_l_solve.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.POINTER(_Dense), ctypes.c_void_p]
        lib.cholmod_l_free_factor.argtypes = [ctypes.POINTER(ctypes.c_void_p), ctypes.c_void_p]
        lib.cholmod_l_free_dense.argtypes = [ctypes.POINTER(ctypes.POINTER(_Dense)), ctypes.c_void_p]
        lib.cholmod_l_start.argtypes = lib.cholmod_l_finish.argtypes = [ctypes.c_void_p]
        return lib
    return None


class Factor:
    """The Cholesky factor of one sparsity pattern: ``analyze`` once, then ``factorize(values)`` and
    ``solve(rhs)`` per matrix. Not for concurrent use; a lock serializes the calls."""

    def __init__(self, lower: sp.csc_matrix) -> None:
        lib = library()
        if lib is None:
            raise ImportError("no CHOLMOD library found (pip install cvxopt)")
        self._lib = lib
        self._lock = threading.Lock()
        self.n = lower.shape[0]
        self._p = np.ascontiguousarray(lower.indptr, np.int64)
        self._i = np.ascontiguousarray(lower.indices, np.int64)
        self._x = np.ascontiguousarray(lower.data, np.float64)
        self._A = _Sparse(self.n, self.n, len(self._i), self._p.ctypes.data, self._i.ctypes.data, None,
                          self._x.ctypes.data, None, -1, _LONG, _REAL, _DOUBLE, 1, 1)
        self._common = ctypes.create_string_buffer(_COMMON_BYTES)
        lib.cholmod_l_start(self._common)
        _quiet(self._common)
        self._L = ctypes.c_void_p(lib.cholmod_l_analyze(ctypes.byref(self._A), self._common))
        if not self._L.value:
            lib.cholmod_l_finish(self._common)
            raise MemoryError("CHOLMOD could not analyse the matrix")

    def same_pattern(self, lower: sp.csc_matrix) -> bool:
        return (lower.shape[0] == self.n and np.array_equal(lower.indptr, self._p)
                and np.array_equal(lower.indices, self._i))

    def factorize(self, data: np.ndarray) -> bool:
        """Numeric factorization of the pattern with these values; False when the matrix is not
        positive definite (to rounding)."""
        with self._lock:
            self._x[:] = data
            ok = self._lib.cholmod_l_factorize(ctypes.byref(self._A), self._L, self._common)
            minor = _FactorHead.from_address(self._L.value).minor
        return bool(ok) and minor >= self.n

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        b = np.asfortranarray(rhs, dtype=np.float64)
        nrhs = 1 if b.ndim == 1 else b.shape[1]
        B = _Dense(self.n, nrhs, self.n * nrhs, self.n, b.ctypes.data, None, _REAL, _DOUBLE)
        with self._lock:
            X = self._lib.cholmod_l_solve(_SYS_A, self._L, ctypes.byref(B), self._common)
            if not X:
                raise MemoryError("CHOLMOD solve failed")
            out = np.ctypeslib.as_array(ctypes.cast(X.contents.x, ctypes.POINTER(ctypes.c_double)),
                                        shape=(nrhs, self.n)).T.copy()
            self._lib.cholmod_l_free_dense(ctypes.byref(X), self._common)
        return out.reshape(rhs.shape)

    def __del__(self) -> None:
        lib = getattr(self, "_lib", None)
        if lib is not None and getattr(self, "_L", None) is not None and self._L.value:
            lib.cholmod_l_free_factor(ctypes.byref(self._L), self._common)
            lib.cholmod_l_finish(self._common)
            self._L = None

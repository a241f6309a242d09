"""Array back ends, so that every closed form is written once.

The physics in :mod:`fogref.media` is written against a tiny namespace ``ops``
that is either :data:`NP` (numpy, float64, used for references and analysis) or
:func:`drjit_ops` (Dr.Jit, the variant's float type, usually float32, used inside
the renderer).  The two back ends differ only in their primitives; the formulas
are shared, and ``tests/test_media_twins.py`` holds the two forms equal.

Dr.Jit has no ``expm1``/``log1p``; they are built here from ``exp``/``log``
with Kahan's correction, which is accurate to a few ulp (W. Kahan, "Interval
arithmetic options in the proposed IEEE floating point arithmetic standard",
1980; also Goldberg 1991, Theorem 4).
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Literal, TypeAlias

import numpy as np

#: A value of the array back ends: a Python float, a numpy float64 array or a Dr.Jit ``Float``
#: (or its ``Bool``/``Mask``).  Dr.Jit ships no type stubs, so to the type checker it is ``Any``;
#: the name says what the physics means.
Real: TypeAlias = Any


class NumpyOps:
    """numpy float64 back end."""

    name = "numpy"
    dtype = np.float64
    largest = float(np.finfo(np.float64).max)
    #: exponent arguments are clamped to +-EXP_LIMIT so exp() never overflows.
    exp_limit = 700.0
    #: log(largest): exp() of anything above overflows.
    log_largest = float(np.log(np.finfo(np.float64).max))
    #: smallest normal number.
    tiny = float(np.finfo(np.float64).tiny)

    @staticmethod
    def asarray(x: Real) -> Real:
        return np.asarray(x, dtype=np.float64)

    @staticmethod
    def param(x: Real, slot: int = 0) -> Real:
        """A scene parameter (a Python number) as it enters array arithmetic: unchanged."""
        return x

    @staticmethod
    def params(values: Real) -> Real:
        """Several scene parameters: a tuple of them, unchanged."""
        return tuple(values)

    exp = staticmethod(np.exp)
    log = staticmethod(np.log)
    expm1 = staticmethod(np.expm1)
    log1p = staticmethod(np.log1p)
    sqrt = staticmethod(np.sqrt)
    abs = staticmethod(np.abs)
    minimum = staticmethod(np.minimum)
    maximum = staticmethod(np.maximum)
    isfinite = staticmethod(np.isfinite)

    @staticmethod
    def where(cond: Real, a: Real, b: Real) -> Real:
        return np.where(cond, a, b)

    @staticmethod
    def safe_div(a: Real, b: Real) -> Real:
        """a / b, with b == 0 giving 0 (callers select the limit themselves)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(b != 0, a / np.where(b != 0, b, 1.0), 0.0)

    @staticmethod
    def errstate() -> np.errstate:
        return np.errstate(all="ignore")

    @staticmethod
    def interp(x: Real, xp: tuple, fp: tuple) -> Real:
        """Linear interpolation of the table ``(xp, fp)`` (``xp`` increasing) at ``x``,
        clamped to the table's ends."""
        return np.interp(x, xp, fp)

    @staticmethod
    def interp_uniform(x: Real, lo: float, hi: float, fp: tuple) -> Real:
        """Linear interpolation of ``fp`` (``len(fp) >= 2`` values at nodes uniform on
        ``[lo, hi]``) at ``x``, clamped to the ends.

        >>> float(NumpyOps.interp_uniform(0.25, -1.0, 1.0, (0.0, 1.0, 4.0)))
        1.75
        """
        return np.interp(x, np.linspace(lo, hi, len(fp)), fp)


class _NullContext:
    def __enter__(self) -> _NullContext:
        return self

    def __exit__(self, *exc: Any) -> Literal[False]:
        return False


class DrJitOps:
    """Dr.Jit back end for the current Mitsuba variant's ``Float``."""

    name = "drjit"

    def __init__(self, Float: Any) -> None:
        import drjit as dr

        self.dr = dr
        self.Float = Float
        single = dr.type_v(Float) == dr.VarType.Float32
        self.largest = float(np.finfo(np.float32 if single else np.float64).max)
        self.exp_limit = 87.0 if single else 700.0
        fi = np.finfo(np.float32 if single else np.float64)
        self.log_largest = float(np.log(fi.max))
        self.tiny = float(fi.tiny)
        self._params: dict[Any, Any] = {}  # parameter keys (tuples) and table keys (str)

    #: opaque parameters kept (see :meth:`param`); about 100 bytes each
    MAX_PARAMS = 4096

    def asarray(self, x: Real) -> Real:
        return x if isinstance(x, self.Float) else self.Float(x)

    def param(self, x: Real, slot: int = 0) -> Real:
        """A scene parameter (a Python number: density, falloff, ``sigma_t``, ``g``, the
        sun's direction) as it enters array arithmetic: an *opaque* ``Float``, i.e. an
        evaluated one-element array that the kernel reads from memory.  A Python float
        would be traced into the kernel as a literal, so every new value of the
        parameter would compile a new kernel; opaque, one kernel serves every value
        (``dr.opaque``, Dr.Jit's documented way to do this).
        Trace-time branches (is the layer constant? is the sun up?) keep reading the
        Python value.  Arrays pass through unchanged.

        The arrays are memoised per *parameter*: a fresh array per call would give the
        kernel an input per use (a layer's ``log_c`` runs dozens of times per trace), a
        longer kernel and a slower compile (measured in ``CHANGELOG.md``, 0.2.0).  A
        parameter is the calling bytecode, the calling method's ``self`` and ``slot``
        (the channel or axis, where one call site runs in a loop), so that two
        different parameters never share an input because their values happen to be
        equal: the kernel's inputs would then depend on coincidences, and a
        configuration where the values differ would compile again.
        """
        return self._param(x, sys._getframe(1), slot)

    def params(self, values: Real) -> Real:
        """Several scene parameters (RGB, a direction): :meth:`param` with ``slot`` the
        index of the value's first occurrence, so that a grey colour's three channels
        are one input (and Dr.Jit computes their identical arithmetic once, as it does
        for equal literals; one input per channel makes a longer kernel).  A colour that
        turns from grey to RGB compiles again."""
        caller, values = sys._getframe(1), list(values)
        return tuple(self._param(v, caller, values.index(v)) for v in values)

    @contextmanager
    def isolated_params(self, tables: dict | None = None) -> Iterator[DrJitOps]:
        """A scope in which :meth:`param` and :meth:`interp` start from an empty cache, and
        after which the cache is what it was before: what ``dr.freeze`` records must not read
        arrays made before the recording (they are not its inputs), and arrays made while it
        records belong to that recording, not to later traced calls.

        ``tables``: :meth:`tables`' arrays as the frozen function received them (its
        inputs), which :meth:`interp` then uses.  A table can't be made inside a recording:
        Dr.Jit takes an array made from host data there for one made before it.

        >>> ops = DrJitOps.__new__(DrJitOps)  # no Dr.Jit needed to show the scope
        >>> ops._params = {"kept": 1}
        >>> with ops.isolated_params():
        ...     ops._params
        {}
        >>> with ops.isolated_params({"table:2:7": "an array"}):
        ...     ops._params
        {'table:2:7': 'an array'}
        >>> ops._params
        {'kept': 1}
        """
        saved, self._params = self._params, dict(tables or {})
        try:
            yield self
        finally:
            self._params = saved

    def tables(self, *columns: tuple) -> dict:
        """The arrays :meth:`interp` reads for these table columns (tuples of Python numbers),
        uploaded now where they are not yet, keyed as :meth:`interp` finds them: what a
        ``dr.freeze`` recording takes as inputs (:meth:`isolated_params`)."""
        return {self._table_key(c): self._table(c) for c in columns}

    def trim_params(self) -> None:
        """Drop the kept parameters once they fill half of :data:`MAX_PARAMS`.  For a caller to run
        between two traces (fogpath does before each pass): the bound in :meth:`param` is then not
        reached inside a trace, where clearing gives one parameter two inputs and the kernel a new
        hash, so a compile that its values did not need."""
        if len(self._params) >= self.MAX_PARAMS // 2:
            self._params.clear()

    def _param(self, x: Real, caller: Real, slot: Real) -> Real:
        if self.dr.is_array_v(x):
            return x
        owner = caller.f_locals.get("self")
        key = (caller.f_code, caller.f_lasti, id(owner), slot, float(x).hex())  # hex tells -0.0 from 0.0
        value = self._params.get(key)
        if value is None:
            if len(self._params) >= self.MAX_PARAMS:
                self._params.clear()  # bounded: a long sweep sees many values (see trim_params)
            value = self._params[key] = self.dr.opaque(self.Float, x)
        return value

    def _f(self, x: Real) -> Real:
        # Python scalars become Float so that Kahan's tricks run in the variant's
        # precision (and never raise ZeroDivisionError in Python arithmetic).
        return x if isinstance(x, self.Float) else self.Float(x)

    def exp(self, x: Real) -> Real:
        return self.dr.exp(self._f(x))

    def log(self, x: Real) -> Real:
        return self.dr.log(self._f(x))

    def expm1(self, x: Real) -> Real:
        dr = self.dr
        x = self._f(x)
        u = dr.exp(x)
        um1 = u - 1
        big = dr.abs(x) > 0.5
        r = dr.select(u == 1, x, um1 * x / dr.log(u))
        r = dr.select(um1 == -1, -1.0, r)
        return dr.select(big, um1, r)

    def log1p(self, x: Real) -> Real:
        dr = self.dr
        x = self._f(x)
        u = 1 + x
        r = dr.select(u == 1, x, dr.log(u) * x / (u - 1))
        return dr.select(dr.abs(x) > 0.5, dr.log(u), r)

    def sqrt(self, x: Real) -> Real:
        return self.dr.sqrt(x)

    def abs(self, x: Real) -> Real:
        return self.dr.abs(x)

    def minimum(self, a: Real, b: Real) -> Real:
        return self.dr.minimum(a, b)

    def maximum(self, a: Real, b: Real) -> Real:
        return self.dr.maximum(a, b)

    def isfinite(self, x: Real) -> Real:
        return self.dr.isfinite(x)

    def where(self, cond: Real, a: Real, b: Real) -> Real:
        return self.dr.select(cond, a, b)

    def safe_div(self, a: Real, b: Real) -> Real:
        dr = self.dr
        nz = b != 0
        return dr.select(nz, a / dr.select(nz, b, 1.0), 0.0)

    def errstate(self) -> _NullContext:
        return _NullContext()

    def interp(self, x: Real, xp: tuple, fp: tuple) -> Real:
        """Linear interpolation of the table ``(xp, fp)`` (``xp`` increasing, Python
        numbers) at ``x``, clamped to the table's ends: the interval by binary search
        (as Mitsuba's ``IrregularContinuousDistribution``), the tables uploaded once."""
        dr, n = self.dr, len(xp)
        xs, fs = self._table(xp), self._table(fp)
        x = dr.clip(self._f(x), xp[0], xp[-1])
        i = dr.binary_search(1, n - 1, lambda j: dr.gather(self.Float, xs, j) <= x) - 1
        i = dr.clip(i, 0, n - 2)
        x0, x1 = dr.gather(self.Float, xs, i), dr.gather(self.Float, xs, i + 1)
        f0, f1 = dr.gather(self.Float, fs, i), dr.gather(self.Float, fs, i + 1)
        return dr.lerp(f0, f1, (x - x0) / (x1 - x0))

    def interp_uniform(self, x: Real, lo: float, hi: float, fp: tuple) -> Real:
        """Linear interpolation of ``fp`` (Python numbers at ``len(fp) >= 2`` nodes uniform on
        ``[lo, hi]``) at ``x``, clamped to the ends: the interval by one division, two gathers
        (the table uploaded once, as :meth:`interp`'s)."""
        dr, n = self.dr, len(fp)
        fs = self._table(fp)
        t = (dr.clip(self._f(x), lo, hi) - lo) * ((n - 1) / (hi - lo))
        i = dr.minimum(dr.uint32_array_t(self.Float)(t), n - 2)
        f0, f1 = dr.gather(self.Float, fs, i), dr.gather(self.Float, fs, i + 1)
        return dr.lerp(f0, f1, t - self.Float(i))

    @staticmethod
    def _table_key(values: tuple) -> str:
        return f"table:{len(values)}:{hash(values)}"

    def _table(self, values: tuple) -> Real:
        key = self._table_key(values)
        arr = self._params.get(key)
        if arr is None:
            arr = self._params[key] = self.Float(np.asarray(values, dtype=np.float64))
        return arr


#: Either back end, as the physics receives it (``ops`` arguments).
Ops: TypeAlias = "NumpyOps | DrJitOps"

NP = NumpyOps()

_cache: dict = {}


def drjit_ops(Float: Any = None) -> DrJitOps:
    """The Dr.Jit back end for ``Float`` (default: ``mitsuba.Float`` of the variant)."""
    if Float is None:
        import mitsuba as mi

        Float = mi.Float
    if Float not in _cache:
        _cache[Float] = DrJitOps(Float)
    return _cache[Float]

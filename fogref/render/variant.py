"""Mitsuba set-up on an explicit call: LLVM, the variant, fogref's plugins.

:func:`set_variant` is the one place where fogref imports Mitsuba for the
renderer's sake; ``import fogref`` does not call it (see :mod:`fogref`).
"""

from __future__ import annotations

import os

from fogref._llvm import HELP, ensure_llvm
from fogref.errors import FogrefError

DEFAULT_VARIANT = "llvm_ad_rgb"
_registered: set[str] = set()


def set_variant(name: str | None = None) -> str:
    """Set the Mitsuba variant and register fogref's plugins for it.

    Parameters
    ----------
    name
        A Mitsuba variant such as ``"llvm_ad_rgb"`` (default) or
        ``"cuda_ad_rgb"``. None keeps the variant already set, else uses
        ``$FOGREF_VARIANT``, else ``"llvm_ad_rgb"``.

    Returns
    -------
    str
        The variant now set.

    Raises
    ------
    fogref.errors.FogrefError
        The variant is not one of ``mitsuba.variants()``, it fails to start, or
        it is an ``llvm_*`` variant and no LLVM >= 16 was found.

    Notes
    -----
    ``$DRJIT_LIBLLVM_PATH`` is set (:func:`fogref._llvm.ensure_llvm`) before
    Mitsuba is imported, so Dr.Jit's LLVM back end starts with a supported
    LLVM. The plugins (``fogref_plugins.register``: the ``heightfog`` medium
    and the ``fogpath`` integrator) are registered once per variant; Mitsuba
    keeps plugin registrations per variant.
    """
    llvm = ensure_llvm()  # before Dr.Jit starts its LLVM back end
    import mitsuba as mi

    if name is None:
        name = mi.variant() or os.environ.get("FOGREF_VARIANT") or DEFAULT_VARIANT
    if name.startswith("llvm") and not llvm:
        raise FogrefError(HELP)
    if name not in mi.variants():
        raise FogrefError(f"Mitsuba variant '{name}' is not available; choose one of {mi.variants()}")
    if mi.variant() != name:
        try:
            mi.set_variant(name)
        except Exception as e:  # CUDA without a GPU, a broken LLVM, ...
            raise FogrefError(f"cannot use Mitsuba variant '{name}': {e}") from e
    if name not in _registered:
        import fogref_plugins

        fogref_plugins.register()
        _registered.add(name)
    return name

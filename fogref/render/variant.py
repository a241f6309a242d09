"""Variant selection and plugin registration."""

from __future__ import annotations

import os

from fogref._llvm import HELP, ensure_llvm
from fogref.errors import FogrefError

DEFAULT_VARIANT = "llvm_ad_rgb"
_registered: set[str] = set()


def set_variant(name: str | None = None) -> str:
    """Set the Mitsuba variant and register fogref's plugins for it.

    ``name``: a Mitsuba variant such as ``llvm_ad_rgb`` (default) or
    ``cuda_ad_rgb``; None keeps the variant already set, else uses
    ``$FOGREF_VARIANT`` or ``llvm_ad_rgb``.
    """
    import mitsuba as mi

    if name is None:
        name = mi.variant() or os.environ.get("FOGREF_VARIANT") or DEFAULT_VARIANT
    if name.startswith("llvm") and not ensure_llvm():
        raise FogrefError(HELP)
    if name not in mi.variants():
        raise FogrefError(f"Mitsuba variant '{name}' is not available; choose one of {mi.variants()}")
    if mi.variant() != name:
        try:
            mi.set_variant(name)
        except Exception as e:  # CUDA without a GPU, LLVM missing, ...
            raise FogrefError(f"cannot use Mitsuba variant '{name}': {e}") from e
    if name not in _registered:
        import fogref_plugins as plugins

        plugins.register()
        _registered.add(name)
    return name

"""fogref: a physically based reference for real-time fog.

Importing fogref (or :mod:`fogref.media`, :mod:`fogref.models`) does no work:
it neither looks for LLVM nor imports Mitsuba or Dr.Jit. The physics
(:mod:`fogref.media`) and the game models (:mod:`fogref.models`) need neither.

Mitsuba is set up by one explicit call, :func:`set_variant`: it points Dr.Jit at
an LLVM >= 16, selects the variant and registers fogref's plugins (the
``heightfog`` medium and the ``fogpath`` integrator). The render driver and
:func:`fogref.render.load.load_scene` call it; ``mi.load_file`` users call it
themselves::

    import fogref, mitsuba as mi
    fogref.set_variant()                     # llvm_ad_rgb unless told otherwise
    scene = mi.load_file("scenes/valley.xml", parallel=False, res=160, resy=90)

``parallel=False``: Mitsuba 3.9.1's parallel loading can corrupt a ``sunsky`` built after a
render through the Python ``heightfog`` medium (docs/design.md, section 6).

Code that uses Dr.Jit's LLVM arrays without Mitsuba calls :func:`ensure_llvm`
before the first array is built.

Examples
--------
>>> import fogref
>>> fogref.__version__
'0.2.0'
>>> callable(fogref.set_variant) and callable(fogref.ensure_llvm)
True
"""

from __future__ import annotations

import importlib as _importlib  # as _importlib: not a name the facade offers

from fogref._version import __version__
from fogref.llvm import require_llvm as _require_llvm

#: The public API for checking a fog model or an engine's images against a truth
#: (docs/byo.md): name -> module.  Imported on first use (:func:`__getattr__`), so
#: ``import fogref`` stays free of work.
_LAZY = {
    "set_variant": "fogref.render.variant",  # Mitsuba set-up: LLVM, the variant, the plugins
    "load_truth": "fogref.gbuffer",
    "Truth": "fogref.gbuffer",
    "cached_truth": "fogref.render.cache",
    "check": "fogref.compare.check",
    "assert_fog_matches": "fogref.compare.check",
    "evaluate_model": "fogref.compare.candidate",
    "synthetic_truth": "fogref.compare.synthetic",
    "CheckResult": "fogref.compare.results",
    "EngineImages": "fogref.compare.foreign",
    "load_engine_images": "fogref.compare.foreign",
    "read_image": "fogref.compare.foreign",
    "resolve_model": "fogref.models.resolve",
    "build_model": "fogref.mapping.build",
    "fit_model": "fogref.study.fit",
    "translate": "fogref.study.fit",
    "scene_path": "fogref.shipped_scenes",
    "export_engine": "fogref.study.export",
}

__all__ = ["__version__", "ensure_llvm", *_LAZY]


def __getattr__(name: str):
    """``fogref.set_variant``, ``fogref.check``, ...: the public API of :data:`_LAZY`, imported on first
    use."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'fogref' has no attribute '{name}'")
    return getattr(_importlib.import_module(module), name)


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


def ensure_llvm() -> str:
    """Point Dr.Jit at an LLVM >= 16 (``$DRJIT_LIBLLVM_PATH``) and return its path.

    Needed only by code that builds Dr.Jit LLVM arrays (``drjit.llvm.Float``)
    without :func:`set_variant`; call it before the first array is built, since
    Dr.Jit reads the variable when its LLVM back end starts.

    Raises
    ------
    fogref.errors.FogrefError
        No LLVM >= 16 was found and ``$DRJIT_LIBLLVM_PATH`` is unset; the message
        says what to install.
    """
    return _require_llvm()

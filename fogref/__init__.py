"""fogref: a physically based reference for real-time fog.

Importing fogref finds an LLVM for Dr.Jit, selects a Mitsuba variant (the one
already set, else ``$FOGREF_VARIANT``, else ``llvm_ad_rgb``) and registers the
plugins in ``plugins/`` so that ``mi.load_file`` works on fogref's XML scenes.
The physics (:mod:`fogref.media`) and the game models (:mod:`fogref.models`) do
not need Mitsuba; import them as usual.
"""

from fogref._llvm import ensure_llvm as _ensure_llvm

__version__ = "0.1.0"

_ensure_llvm()


def set_variant(name: str | None = None) -> str:
    """Select a Mitsuba variant (default: as above) and register fogref's plugins."""
    from fogref.render.variant import set_variant as _sv

    return _sv(name)


def _autoload():
    import os

    if os.environ.get("FOGREF_NO_MITSUBA"):
        return
    try:
        set_variant(None)
    except ImportError:  # mitsuba not installed: physics and models still work
        pass


_autoload()

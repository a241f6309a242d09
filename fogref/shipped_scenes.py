"""The scenes fogref ships: XML files installed with the package (``fogref/scenes/``).

A checkout shows them as ``scenes/`` (a link to ``fogref/scenes``); an installed fogref has
them under its package folder.  :func:`scene_path` finds one by name, and every door that
takes a scene (``fogref render``, ``fit --scene``, ``translate --scene``, ``fogref_truth``)
also takes the bare name: a value that is no file and has neither a folder nor a suffix is a
shipped scene's name (:func:`resolve_scene`).

Examples
--------
>>> scene_path("valley").name
'valley.xml'
>>> "open_plane" in shipped_scene_names()
True
>>> resolve_scene("valley") == scene_path("valley")
True
>>> scene_path("lake")
Traceback (most recent call last):
...
fogref.errors.ParameterError: fogref.scene_path: parameter 'name': 'lake' is not a shipped scene ...
"""

from __future__ import annotations

import os
from pathlib import Path

from fogref.errors import ParameterError, did_you_mean

__all__ = ["SCENES_DIR", "resolve_scene", "scene_label", "scene_path", "shipped_scene_names"]

#: The folder of the shipped scenes, inside the installed package.
SCENES_DIR = Path(__file__).resolve().parent / "scenes"


def shipped_scene_names() -> list[str]:
    """The names of the shipped scenes (file names without ``.xml``), sorted."""
    return sorted(p.stem for p in SCENES_DIR.glob("*.xml"))


def scene_path(name: str) -> Path:
    """The path of the shipped scene ``name`` (``"valley"``, ``"open_plane"``, ... or
    ``"valley.xml"``); ParameterError naming the shipped scenes for any other name."""
    stem = str(name)[:-4] if str(name).endswith(".xml") else str(name)
    names = shipped_scene_names()
    if stem not in names:
        raise ParameterError(
            "fogref.scene_path",
            "name",
            f"{name!r} is not a shipped scene (one of {', '.join(names)}){did_you_mean(stem, names)}",
        )
    return SCENES_DIR / f"{stem}.xml"


def resolve_scene(value: str | os.PathLike) -> Path:
    """``value`` as a scene path: an existing file as it is; a bare name of a shipped scene
    (no folder, no suffix, no such file here) as :func:`scene_path`; anything else unchanged
    (the reader then says the file is missing)."""
    p = Path(value)
    if p.is_file() or p.suffix or len(p.parts) != 1 or p.name not in shipped_scene_names():
        return p
    return scene_path(p.name)


def scene_label(path: str | os.PathLike) -> str:
    """How reports name a scene: a shipped scene by its name (the same on every install), any
    other by its path as given.

    >>> scene_label(scene_path("open_plane")), scene_label("my/scene.xml")
    ('open_plane (shipped)', 'my/scene.xml')
    """
    p = Path(path)
    try:
        if p.resolve().parent == SCENES_DIR and p.stem in shipped_scene_names():
            return f"{p.stem} (shipped)"
    except OSError:
        pass
    return str(path)

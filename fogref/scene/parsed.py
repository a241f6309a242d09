"""A scene read once: its path, parsed tree, resolved ``$default``s, the files it loads and their digest.

:func:`read_scene` parses the XML (:func:`fogref.scene.defaults.parse_scene`, the one
parse), resolves the ``$default``s after the ``--set`` overrides (checked against
:data:`fogref.scene.vocabulary.RANGES`) and returns a :class:`ParsedScene`; the render
driver makes one per render and hands it to the cache key, the description
(:func:`fogref.render.load.describe_scene`), the loader (:func:`fogref.render.load.load_scene`)
and the studies, so no one parses the file again.  The files the scene loads and their
digest (:mod:`fogref.scene.inputs`) are listed from a copy of the same tree on first use.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> d = Path(tempfile.mkdtemp())
>>> _ = (d / "s.xml").write_text('<scene version="3.0.0"><default name="res" value="64"/></scene>')
>>> s = read_scene(d / "s.xml", {"res": 32})
>>> s.defaults, [i.kind for i in s.inputs], len(s.digest)
({'res': '32'}, ['scene'], 64)
"""

from __future__ import annotations

import copy
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from fogref import params
from fogref.scene.defaults import parse_scene, resolve
from fogref.scene.inputs import SceneInput, inputs_digest, scene_inputs


@dataclass(frozen=True, eq=False)
class ParsedScene:
    """A fogref scene as read once (:func:`read_scene`).

    ``path``: the scene file; ``root``: its parsed XML tree (``$name``s not substituted:
    never modify it, copy it); ``overrides``: the ``--set`` values as given; ``defaults``:
    every ``$default`` after the overrides (text).  Its description is
    :func:`fogref.render.load.describe_scene` of it (a ``sunsky``'s needs Mitsuba).
    """

    path: Path
    root: ET.Element
    overrides: dict
    defaults: dict[str, str]

    @cached_property
    def inputs(self) -> tuple[SceneInput, ...]:
        """The scene file and every file it loads (:func:`fogref.scene.inputs.scene_inputs`)."""
        return tuple(scene_inputs(self.path, self.overrides, root=copy.deepcopy(self.root)))

    @cached_property
    def _digest(self) -> tuple[str, dict]:
        record: dict = {}
        return inputs_digest(self.path, self.overrides, list(self.inputs), record=record), record

    @property
    def digest(self) -> str:
        """SHA-256 (hex) of the scene and every file it loads (:func:`fogref.scene.inputs.inputs_digest`)."""
        return self._digest[0]

    @property
    def input_hashes(self) -> dict:
        """``{path: SHA-256 or "missing"}`` of the loaded files other than the scene (a truth's
        ``fogref.inputs`` header)."""
        return dict(self._digest[1])


def read_scene(path, overrides: dict | None = None) -> ParsedScene:
    """Parse the scene at ``path`` once and resolve its ``$default``s after ``overrides``.

    Raises :class:`~fogref.errors.FogrefError` naming the file for a missing file or
    malformed XML, and :class:`~fogref.errors.ParameterError` for an override the scene does
    not declare or a value outside its range (:func:`fogref.scene.defaults.resolve`).
    """
    path = params.path(path, "scene", source="fogref")
    root = parse_scene(path)
    defaults = resolve(root, overrides, source=path)
    return ParsedScene(path, root, dict(overrides or {}), defaults)

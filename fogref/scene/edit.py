"""Edited copies of a fogref scene: without its sun, with another fog.

Each edit reads the scene with :func:`fogref.scene.defaults.parse_scene` (its comments kept where
the copy is for people to read) and writes a new XML file; the original is never changed.

* :func:`sunless_scene`: the scene without its ``directional`` emitter(s), for sky-only renders
  (the Unreal study's budget, the sweeps).  Its first element is ``<path value="SCENE'S FOLDER"/>``,
  so the files it names relatively resolve where the original's do.
* :func:`replace_fog`: the sensor's ``heightfog`` with other parameters (UE's path-traced fog,
  :func:`fogref.mapping.unreal_pathtracer.rewrite_scene`), each value optionally a ``<default>``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from fogref.atomic import write_text_atomic
from fogref.errors import ParameterError
from fogref.scene.defaults import parse_scene
from fogref.scene.parsed import ParsedScene

__all__ = ["replace_fog", "sunless_scene"]


def sunless_scene(scene, out_dir: Path) -> Path:
    """A copy of ``scene`` (a path or a :class:`~fogref.scene.parsed.ParsedScene`) without its
    ``directional`` emitter(s) (sky-only light), written in ``out_dir`` as ``<stem>_nosun.xml``.

    Its first element is ``<path value="SCENE'S FOLDER"/>``, so the meshes, envmaps and textures
    it names relatively resolve where the original's do (Mitsuba's search path;
    :func:`fogref.scene.inputs.scene_inputs` follows it, so the copy's cache keys cover the
    original's files).  An unchanged copy is not written again (its mtime is kept).

    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "s.xml").write_text('<scene><emitter type="directional"/><emitter type="constant"/></scene>')
    >>> out = sunless_scene(d / "s.xml", d / "renders")
    >>> out.name, out.read_text().count("emitter")
    ('s_nosun.xml', 1)
    """
    path = scene.path if isinstance(scene, ParsedScene) else Path(scene)
    root = parse_scene(path)  # a fresh tree: this copy is edited
    root.insert(0, ET.Element("path", value=str(path.resolve().parent)))
    for parent in list(root.iter()):
        for ch in list(parent):
            if ch.tag == "emitter" and ch.get("type") == "directional":
                parent.remove(ch)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    out = out_dir / f"{path.stem}_nosun.xml"
    text = ET.tostring(root, encoding="unicode")
    if not (out.is_file() and out.read_text() == text):  # keep the mtime: the renders are cached on it
        write_text_atomic(out, text)
    return out


def _tag(name: str, value) -> tuple[str, str]:
    """The XML tag and text of one ``heightfog`` parameter (``center``: a point; colours: rgb)."""
    if isinstance(value, str):
        return "string", value
    if isinstance(value, (list, tuple)):
        return ("point" if name == "center" else "rgb"), ", ".join(repr(float(x)) for x in value)
    return "float", repr(float(value))


def replace_fog(src, dst, params: dict, default_names: dict | None = None) -> None:
    """Copy the fogref scene ``src`` to ``dst`` with its ``heightfog``'s parameters replaced by
    ``params`` (name -> number, list of 3 numbers or text; ``center`` is a point, other lists rgb).

    ``default_names``: with it, each value but ``profile`` becomes a ``<default>``
    (``default_names.get(name, name)``, declared after the scene's own or updated in place) and
    the medium refers to it as ``$name``; ``center`` refers to its default without setting it
    (the camera's own, e.g. ``$camera_origin``: the fog follows the camera).  The medium's
    ``phase`` child and the scene's comments are kept.

    Raises :class:`~fogref.errors.ParameterError` naming ``src`` when it has no heightfog.
    """
    root = parse_scene(src, comments=True)
    med = next((m for m in root.iter("medium") if m.get("type") == "heightfog"), None)
    if med is None:
        raise ParameterError(str(src), "medium", "the scene has no heightfog medium to replace")
    for child in [c for c in med if c.get("name") is not None and c.tag != "phase"]:
        med.remove(child)
    defaults = {e.get("name"): e for e in root.findall("default")}
    at = max((i + 1 for i, e in enumerate(root) if e.tag == "default"), default=0)
    for k, v in params.items():
        tag, text = _tag(k, v)
        if default_names is not None and k != "profile":
            name = default_names.get(k, k)
            if k != "center":  # the camera's own default
                if name not in defaults:
                    defaults[name] = ET.Element("default", name=name)
                    root.insert(at, defaults[name])
                    at += 1
                defaults[name].set("value", text)
            text = f"${name}"
        ET.SubElement(med, tag, name=k, value=text)
    tree = ET.ElementTree(root)
    ET.indent(tree, space="    ")
    tree.write(dst, encoding="unicode", xml_declaration=True)

"""Every file a scene loads, found the way Mitsuba finds it, and one digest of them all.

A truth's pixels depend on the scene XML and on every file it loads: meshes
(``obj``/``ply``/``serialized`` ``filename``), environment maps and bitmap textures
(``filename``), spectra (``<spectrum filename=...>``), included XML
(``<include filename=...>``), and whichever of these a ``$default`` (or an override
of it) selects.  :func:`scene_inputs` lists them from the parsed XML, following
Mitsuba 3's parser (``src/core/parser.cpp``: ``substitute_parameters``, the
``Default``, ``Include`` and ``Resource`` tags) and file resolver
(``src/core/fresolver.cpp``):

* ``$name`` in any attribute is replaced by the overrides, then by the
  ``<default>``s met so far in document order (a default never replaces an
  override or an earlier default); the longest name is replaced first; ``\\$`` is
  a literal ``$``.
* A relative ``<include>`` or ``<spectrum filename>`` is looked up in the folders
  of that XML file's resolver (its ``<path>`` folders, newest first, then the
  file's own folder, then the including file's resolver), else taken relative to
  the working directory.  ``<string>`` properties are opened by the plugins at
  instantiation with the top-level scene's resolver (``<path>`` folders of the
  scene, the scene's folder, the working directory): a ``filename`` of an included
  file is *not* looked up next to that included file.
* A ``<string>`` counts as an input when its name is ``filename`` (every Mitsuba
  plugin that reads a file takes it so), or when its value names an existing file
  (Mitsuba's own ``transform_relocate`` treats such strings as assets).

:func:`inputs_digest` hashes ``(path, size, SHA-256 of the content)`` of the scene
and of each input, in order; every key that must change with a truth's pixels
(the render checkpoint, the render cache, :func:`fogref.cached_truth`, a sweep's
configuration id) uses it.  Content hashes are memoised in-process on
``(device, inode, size, mtime, ctime)``, trusted only for files last modified
well before they were hashed (git's "racy clean" rule,
``Documentation/technical/racy-git.txt``).

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> d = Path(tempfile.mkdtemp())
>>> _ = (d / "a.obj").write_text("v 0 0 0\\n")
>>> _ = (d / "b.obj").write_text("v 0 0 1\\n")
>>> _ = (d / "s.xml").write_text('<scene version="3.0.0"><default name="mesh" value="a.obj"/>'
...     '<shape type="obj"><string name="filename" value="$mesh"/></shape></scene>')
>>> [(i.kind, i.path.name) for i in scene_inputs(d / "s.xml")]
[('scene', 's.xml'), ('shape', 'a.obj')]
>>> [i.path.name for i in scene_inputs(d / "s.xml", {"mesh": "b.obj"})]
['s.xml', 'b.obj']
>>> inputs_digest(d / "s.xml") == inputs_digest(d / "s.xml", {"mesh": "b.obj"})
False
"""

from __future__ import annotations

import hashlib
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from fogref.errors import FogrefError
from fogref.scene.defaults import parse_scene, substitute

#: Mitsuba's limit on nested ``<include>`` (``ParserConfig.max_include_depth``).
MAX_INCLUDE_DEPTH = 15
#: Seconds a file must have been unmodified when hashed for its memoised hash to be trusted.
_RACY_SECONDS = 2.0
_MEMO: dict = {}


@dataclass(frozen=True)
class SceneInput:
    """One file a scene loads.

    ``path``: where Mitsuba opens it (absolute, symlinks kept); ``kind``: the element
    that names it (``scene``, ``include``, ``shape``, ``emitter``, ``texture``,
    ``spectrum``, ...); ``source``: the XML file and element that name it;
    ``exists``: whether it is a regular file now; ``plugin``: the naming element's ``type``.
    """

    path: Path
    kind: str
    source: str
    exists: bool
    plugin: str = ""

    @property
    def label(self) -> str:
        """What the file is, for messages: ``"mesh"``, ``"envmap"``, ``"texture"``, ``"scene file"``...

        >>> SceneInput(Path("sky.exr"), "emitter", "s.xml", True, "envmap").label
        'envmap'
        """
        named = {
            "scene": "scene file",
            "include": "included XML",
            "spectrum": "spectrum file",
            "shape": "mesh",
            "texture": "texture",
            "volume": "volume grid",
        }
        if self.kind == "emitter" and self.plugin == "envmap":
            return "envmap"
        other = f"{self.kind} '{self.plugin}' file" if self.plugin else f"{self.kind} file"
        return named.get(self.kind, other)


def _global_resolver() -> list[Path]:
    """Mitsuba's global file resolver: its folders if Mitsuba is loaded, else the working directory."""
    mi = sys.modules.get("mitsuba")
    if mi is not None and hasattr(mi, "file_resolver"):
        try:
            fr = mi.file_resolver()
            return [Path(str(fr[i])) for i in range(len(fr))]
        except Exception:  # an unset variant or an older binding: the default (the working directory)
            pass
    return [Path.cwd()]


def _resolve(name: str, folders: list[Path]) -> Path:
    """Mitsuba's ``FileResolver::resolve``: the first existing ``folder / name``, else ``name``."""
    p = Path(name)
    if not p.is_absolute():
        for base in folders:
            if _names_file(base / p, "exists"):
                return Path(os.path.abspath(base / p))
    return Path(os.path.abspath(p))


class _Walker:
    """One pass over a scene's XML in Mitsuba's order, collecting the files it loads."""

    def __init__(self, scene: Path, overrides: dict | None):
        self.scene = scene
        self.params = [(str(k), str(v)) for k, v in (overrides or {}).items()]
        self.found: list[SceneInput] = []
        self.strings: list[tuple] = []  # (value, kind, plugin, source, named 'filename')
        self.top_resolver: list[Path] = []

    def add(self, path: Path, kind: str, source: str, plugin: str = "") -> None:
        self.found.append(SceneInput(path, kind, source, path.is_file(), plugin))

    def file(self, path: Path, resolver: list[Path], depth: int, top: bool = False, root=None) -> None:
        if depth >= MAX_INCLUDE_DEPTH:
            raise FogrefError(f"{path}: more than {MAX_INCLUDE_DEPTH} nested <include>s")
        root = parse_scene(path) if root is None else root
        own = [Path(os.path.abspath(path.parent))] + resolver
        self.node(root, path, own, depth, parent=None)
        if top:
            self.top_resolver = own

    def node(self, el, path: Path, resolver: list[Path], depth: int, parent) -> None:
        for k, v in el.attrib.items():
            if "$" in v:
                el.set(k, substitute(v, self.params))
        tag, where = el.tag, f"{path.name}: <{parent.tag if parent is not None else 'scene'}"
        where += f" type='{parent.get('type')}'>" if parent is not None and parent.get("type") else ">"
        if tag == "default":
            name = el.get("name")
            if name and all(n != name for n, _ in self.params):
                self.params.append((name, el.get("value", "")))
        elif tag == "path" and el.get("value"):
            folder = _resolve(el.get("value"), resolver)
            resolver.insert(0, folder)
        elif tag == "include" and el.get("filename") is not None:
            inc = _resolve(el.get("filename"), resolver)
            self.add(inc, "include", f"{path.name}: <include>")
            if inc.is_file():
                self.file(inc, list(resolver), depth + 1)
        elif tag == "spectrum" and el.get("filename"):
            self.add(_resolve(el.get("filename"), resolver), "spectrum", where)
        elif tag == "string" and parent is not None and el.get("value"):
            self.strings.append(
                (el.get("value"), parent.tag, parent.get("type", ""), where, el.get("name") == "filename")
            )
        if tag == "transform":
            for c in el:
                for k, v in c.attrib.items():
                    if "$" in v:
                        c.set(k, substitute(v, self.params))
            return
        for c in el:
            self.node(c, path, resolver, depth, parent=el)


def scene_inputs(scene, overrides: dict | None = None, root=None) -> list[SceneInput]:
    """The scene file and every file it loads, in document order, each once.

    Parameters
    ----------
    scene : path
        A Mitsuba XML scene.
    overrides : dict, optional
        ``$name`` values as given to ``mitsuba.load_file`` (``fogref render --set``).
    root : xml.etree.ElementTree.Element, optional
        The scene's parsed tree, if already parsed (it is modified: pass a copy).

    Returns a list of :class:`SceneInput`, the scene first.  A file named but missing
    is listed with ``exists=False`` (Mitsuba refuses the scene when it loads it).
    Raises :class:`~fogref.errors.FogrefError` for a missing scene or malformed XML.
    """
    scene = Path(scene)
    if not scene.is_file():
        raise FogrefError(f"{scene}: no such scene file")
    w = _Walker(scene, overrides)
    w.add(Path(os.path.abspath(scene)), "scene", str(scene))
    w.file(scene, _global_resolver(), 0, top=True, root=root)
    for value, kind, plugin, where, is_filename in w.strings:
        p = _resolve(value, w.top_resolver)
        if is_filename or _names_file(p, "is_file"):
            w.add(p, kind, where, plugin)
    seen, out = set(), []
    for i in w.found:
        if i.path not in seen:
            seen.add(i.path)
            out.append(i)
    return out


def _names_file(p: Path, test: str) -> bool:
    """``p.exists()`` or ``p.is_file()`` (``test``), False for a string no file can be named
    by (e.g. a phase table's numbers, longer than the system's path limit)."""
    try:
        return bool(getattr(p, test)())
    except OSError:
        return False


def file_sha256(path) -> str:
    """SHA-256 of a file's bytes (hex), memoised on the file's identity and times.

    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "x.txt"
    >>> _ = p.write_bytes(b"fog")
    >>> file_sha256(p)[:16]
    'b04216546057e865'
    """
    path = Path(path)
    st = path.stat()
    ident = (os.path.realpath(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)
    hit = _MEMO.get(ident)
    if hit is not None:
        return hit
    now = time.time()
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    digest = h.hexdigest()
    if max(st.st_mtime_ns, st.st_ctime_ns) / 1e9 < now - _RACY_SECONDS:  # not "racily clean"
        _MEMO[ident] = digest
    return digest


def _label(path: Path, folder: Path) -> str:
    """``path`` relative to the scene's folder when inside it (a moved project keeps its keys),
    else absolute."""
    try:
        return path.relative_to(folder).as_posix()
    except ValueError:
        return path.as_posix()


def inputs_digest(
    scene, overrides: dict | None = None, inputs: list | None = None, record: dict | None = None
) -> str:
    """SHA-256 (hex) of the scene file and every file it loads: path, size and content of each.

    Parameters
    ----------
    scene : path
        A Mitsuba XML scene.
    overrides : dict, optional
        ``$name`` values (they select files through ``$default``s).
    inputs : list of SceneInput, optional
        :func:`scene_inputs` of the same scene and overrides, if already listed.
    record : dict, optional
        Filled with ``{path: SHA-256 or "missing"}`` of the inputs other than the scene
        (what a truth's header records as ``fogref.inputs``).

    Paths are relative to the scene's folder when inside it; the scene's own name is
    left out (a renamed copy of a scene renders the same pixels).  A missing input is
    hashed as missing.  Raises :class:`~fogref.errors.FogrefError` as :func:`scene_inputs`.
    This is the one digest of a scene's inputs: the render checkpoint, the render cache
    and a sweep's configuration id use it.
    """
    scene = Path(scene)
    folder = Path(os.path.abspath(scene.parent))
    h = hashlib.sha256(b"fogref.inputs 1\n")
    for i in scene_inputs(scene, overrides) if inputs is None else inputs:
        label = "" if i.kind == "scene" else _label(i.path, folder)
        try:
            sha = file_sha256(i.path)
            line = f"{i.kind}\0{label}\0{i.path.stat().st_size}\0{sha}\n"
        except OSError:  # missing (Mitsuba will say so when it loads the scene) or unreadable
            sha, line = "missing", f"{i.kind}\0{label}\0missing\n"
        h.update(line.encode())
        if record is not None and i.kind != "scene":
            record[label] = sha
    return h.hexdigest()

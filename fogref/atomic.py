"""Safe outputs: a file appears only when complete, and no output replaces an input.

Each writer writes a temporary file in the destination folder, then renames it
over the destination (``os.replace``, atomic on POSIX within one file system).
Only a regular file (or a new name) is replaced so: a device (``/dev/null``,
``/dev/stdout``), a FIFO, or ``-`` (standard output) is written in place, and a
failed write there (``/dev/full``: no space left) is a one-line
:class:`~fogref.errors.FogrefError`.
Every fogref output goes through :func:`atomic_write`: EXRs
(:func:`fogref.exrio.write_exr`), render checkpoints and previews, report text
and figures.  :func:`staged_write` is the same with the write in a ``with`` block:
a truth's sums, written in a thread beside its EXR, land only after it.  Before
any work, a command compares its outputs with its inputs (:func:`refuse_overwriting_inputs`).

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> folder = Path(tempfile.mkdtemp())
>>> write_text_atomic(folder / "sub" / "a.md", "# fog").read_text()
'# fog'
>>> def broken(tmp):
...     Path(tmp).write_text("half")
...     raise OSError("disk full")
>>> atomic_write(folder / "b.txt", broken)
Traceback (most recent call last):
...
OSError: disk full
>>> sorted(p.name for p in folder.iterdir())      # no b.txt, no temporary left behind
['sub']
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import stat
import sys
import tempfile
from pathlib import Path

import numpy as np

from fogref.errors import FogrefError


def _file_mode(path: Path) -> int:
    """The existing file's mode, else 0666 less the process umask."""
    try:
        return path.stat().st_mode & 0o777
    except FileNotFoundError:
        mask = os.umask(0)
        os.umask(mask)
        return 0o666 & ~mask


def is_stream(path) -> bool:
    """True for ``-`` (standard output) and for an existing path that is not a regular file nor a
    folder (a character device such as ``/dev/null``, a FIFO, a socket): written in place, never
    replaced.

    >>> is_stream("-"), is_stream("/dev/null"), is_stream("no/such/file.json"), is_stream("/")
    (True, True, False, False)
    """
    if str(path) == "-":
        return True
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def check_output_file(path, what: str = "output") -> None:
    """A one-line :class:`~fogref.errors.FogrefError` if ``path`` cannot be an output file: an existing
    folder, or under an existing path that is not a folder.  Call it before any work.

    >>> check_output_file("/tmp")
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: output: /tmp is a folder; give a file name
    >>> check_output_file("-"), check_output_file("/dev/null")
    (None, None)
    """
    p = Path(path)
    if is_stream(p):
        return
    if p.is_dir():
        raise FogrefError(f"{what}: {p} is a folder; give a file name")
    for parent in p.parents:
        if parent.exists():
            if not parent.is_dir():
                raise FogrefError(f"{what}: {p}: {parent} is not a folder")
            break


def _write_stream(path, write) -> None:
    """``write`` a temporary file, then copy it into the stream ``path`` (``-``: standard output);
    a failed write is a one-line FogrefError naming ``path`` and the reason."""
    fd, tmp = tempfile.mkstemp(suffix=".tmp" + Path(str(path)).suffix)
    os.close(fd)
    try:
        write(tmp)
        with open(tmp, "rb") as src:
            if str(path) == "-":
                sys.stdout.flush()
                shutil.copyfileobj(src, sys.stdout.buffer)
                sys.stdout.buffer.flush()
            else:
                with open(path, "wb") as dst:
                    shutil.copyfileobj(src, dst)
    except OSError as e:
        if isinstance(e, BrokenPipeError):
            raise
        raise FogrefError(f"{path}: could not write: {e.strerror or e}") from e
    finally:
        os.unlink(tmp)


def atomic_write(path, write) -> Path:
    """Call ``write(tmp_path)``, then rename the temporary file onto ``path``.

    Parameters
    ----------
    path
        Destination; its parent folders are created.
    write
        Callable that writes the whole file at the ``str`` path it is given. The
        temporary file sits in ``path``'s folder and keeps ``path``'s suffix, so
        writers that infer the format from the suffix still work.

    Returns
    -------
    pathlib.Path
        ``path``.

    Notes
    -----
    If ``write`` raises (or is interrupted), the temporary file is removed, the
    exception propagates and ``path`` keeps its previous content, if any.  A stream
    (:func:`is_stream`: ``-``, a device, a FIFO) is written in place, not replaced.
    """
    if is_stream(path):
        _write_stream(path, write)
        return Path(path)
    with staged_write(path) as tmp:
        write(tmp)
    return Path(path)


@contextlib.contextmanager
def staged_write(path):
    """A temporary file beside ``path`` that replaces it when the ``with`` block ends normally.

    Yields the temporary file's ``str`` path (created empty, in ``path``'s folder, with its
    suffix; :func:`temporary_names`), to be written during the block, also by another thread
    that the block waits for.  When the block ends normally, the file takes the mode ``path``
    had (or a plain ``open()``'s) and replaces ``path``.  When it raises or is interrupted, the
    file is removed, ``path`` keeps its content, and the exception propagates.  So one file
    can be written beside another and land only after it (:func:`atomic_write` is one block).

    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with staged_write(folder / "a.txt") as tmp:
    ...     _ = Path(tmp).write_text("first")
    >>> try:
    ...     with staged_write(folder / "a.txt") as tmp:
    ...         _ = Path(tmp).write_text("second")
    ...         raise OSError("the other file could not be written")
    ... except OSError:
    ...     pass
    >>> [(p.name, p.read_text()) for p in folder.iterdir()]
    [('a.txt', 'first')]
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = tmp = None
    try:  # an interruption anywhere from here on leaves no temporary file
        fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp" + path.suffix, dir=path.parent)
        os.close(fd)
        fd = None
        yield tmp
        os.chmod(tmp, _file_mode(path))  # mkstemp makes 0600; give the mode a plain open() would
        os.replace(tmp, path)
    except BaseException:
        if fd is not None:
            try:
                os.close(fd)
            except OSError:  # closed already, just before the interruption
                pass
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        raise


def temporary_names(path) -> str:
    """A regular expression matching the names of :func:`atomic_write`'s temporary files for ``path``
    (what a writer killed mid-write leaves): ``<name>.<random letters, digits, _>.tmp<suffix>``.

    >>> import re
    >>> bool(re.fullmatch(temporary_names("a.exr"), "a.exr.k3_x9zq1.tmp.exr")), bool(re.fullmatch(
    ...     temporary_names("a.exr"), "a.exr.my notes.tmp.exr"))
    (True, False)
    """
    path = Path(path)
    return re.escape(path.name) + r"\.[a-z0-9_]+\.tmp" + re.escape(path.suffix)


def write_text_atomic(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path."""
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


#: The resolution of fogref's saved figures [dots per inch].
FIGURE_DPI = 110


#: zlib level of fogref's PNG figures (0-9; Pillow's default is 6).  At 3 a 320x180 compare report's
#: ten figures encode 1.8x as fast as at 6, for 6.5 % more bytes (``reports/benchmarks/compare_speed.md``).
FIGURE_PNG_COMPRESSION = 3


def figure_save_options(fmt: str = "png", dpi: int = FIGURE_DPI) -> dict:
    """The keyword arguments of ``Figure.savefig`` for every figure fogref writes in format ``fmt``:
    ``dpi``, a tight bounding box and, for PNG, :data:`FIGURE_PNG_COMPRESSION`.

    >>> figure_save_options()["pil_kwargs"], figure_save_options("svg").get("pil_kwargs")
    ({'compress_level': 3}, None)
    """
    options: dict = {"format": fmt, "dpi": dpi, "bbox_inches": "tight"}
    if fmt == "png":
        options["pil_kwargs"] = {"compress_level": FIGURE_PNG_COMPRESSION}
    return options


def save_figure_atomic(figure, path, dpi: int = FIGURE_DPI) -> Path:
    """Save a matplotlib ``Figure`` to ``path`` (format from the suffix) atomically."""
    options = figure_save_options(Path(path).suffix.lstrip(".") or "png", dpi)
    return atomic_write(path, lambda tmp: figure.savefig(tmp, **options))


def savez_atomic(path, **arrays) -> Path:
    """``numpy.savez`` to ``path`` atomically (``path`` should end in ``.npz``)."""
    return atomic_write(path, lambda tmp: np.savez(tmp, **arrays))


def set_aside(path, suffix: str) -> Path:
    """Rename ``path`` to the first unused name of ``<name><suffix>``, ``<name><suffix>1``, ... and
    return it: a damaged input is kept for inspection, never deleted, and no earlier one is replaced.
    An ``OSError`` of the rename propagates.

    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> for text in ("first", "second"):
    ...     _ = (folder / "r.json").write_text(text)
    ...     print(set_aside(folder / "r.json", ".bad").name)
    r.json.bad
    r.json.bad1
    """
    path = Path(path)
    aside, n = path.with_name(path.name + suffix), 1
    while aside.exists() or aside.is_symlink():
        aside, n = path.with_name(f"{path.name}{suffix}{n}"), n + 1
    os.replace(path, aside)
    return aside


def _entries(items):
    """``(path, label)`` pairs from paths, ``(path, label)`` pairs or objects with ``.path`` and
    ``.label`` (or ``.kind``)."""
    for it in items:
        if isinstance(it, tuple):
            yield Path(it[0]), str(it[1])
        elif hasattr(it, "path"):
            yield Path(it.path), str(getattr(it, "label", None) or getattr(it, "kind", "input"))
        else:
            yield Path(it), "input"


def _same(a: Path, b: Path) -> bool:
    """Same file: equal resolved paths (symlinks followed, also for paths not yet created), or
    ``os.path.samefile`` for two existing paths (hard links, case-insensitive file systems)."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def refuse_overwriting_inputs(outputs, inputs, what: str = "output") -> None:
    """Raise a one-line :class:`~fogref.errors.FogrefError` if an output is one of the inputs.

    Call it before any work, with every file the command will write (derived ones too:
    previews, checkpoints, reports) and every file it reads.

    Parameters
    ----------
    outputs, inputs
        Paths, ``(path, label)`` pairs, or objects with ``.path`` and ``.label`` (e.g.
        :class:`fogref.scene.inputs.SceneInput`); labels name them in the message.
    what
        How the user named the outputs, e.g. ``"--out x.exr"``.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "sky.exr").write_bytes(b"v/1")
    >>> os.symlink(d / "sky.exr", d / "link.exr")
    >>> refuse_overwriting_inputs([d / "out.exr"], [(d / "sky.exr", "envmap")], "--out")
    >>> try:
    ...     refuse_overwriting_inputs([(d / "link.exr", "EXR")], [(d / "sky.exr", "envmap")], "--out")
    ... except FogrefError as e:
    ...     print(str(e).replace(str(d), "D").replace("; ", ";\\n"))
    --out: the EXR D/link.exr would overwrite the envmap D/sky.exr, which is an input;
    choose another output
    """
    ins = list(_entries(inputs))
    for out, olabel in _entries(outputs):
        for inp, ilabel in ins:
            if _same(out, inp):
                raise FogrefError(
                    f"{what}: the {olabel} {out} would overwrite the {ilabel} {inp}, which is "
                    f"an input; choose another output"
                )

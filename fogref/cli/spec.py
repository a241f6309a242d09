"""Options declared once: a dataclass per subcommand, from which its argparse parser is built.

Each subcommand module (:mod:`fogref.cli.render`, ...) declares ``Options``, a dataclass
whose fields are made by :func:`option` or :func:`switch`: the default, the check (one
of :mod:`fogref.cli.checks`, which call :mod:`fogref.params`, fogref's one validator), the
unit and range, the help text and, where a Python API function has the same parameter,
that function's name (``api="fogref.render.render:render"``), so that
``tests/test_cli_spec.py`` can assert that both defaults are equal.  The help line of an
option is its help text, then the allowed range with its unit (from the check), then the
default (from the field): each written once.

Parsing (:func:`parse_options`) gives the option values as converted by their checks, and the set
of options the user gave, so that a subcommand can refuse options that do not apply to
its mode.  Refused as usage errors (exit 2, one line ``fogref: error: ...``): an option
given twice (``--spp 4 --spp 8``), a ``NAME=VALUE`` option naming one NAME twice, and
every value its check refuses.

Examples
--------
>>> from dataclasses import dataclass
>>> from fogref.cli.checks import Integer
>>> @dataclass
... class Demo:
...     spp: int = option(64, "samples per pixel", check=Integer(1, 1 << 20))
...     quiet: bool = switch("no progress bar")
>>> p = Parser(prog="demo")
>>> add_options(p, Demo)
>>> opts, given = parse_options(p.parse_args(["--spp", "8"]), Demo, "demo")
>>> opts, sorted(given)
(Demo(spp=8, quiet=False), ['spp'])
>>> " ".join(p.format_help().split()).count("samples per pixel; an integer in [1, 1048576] (default 64)")
1
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from dataclasses import MISSING, field

from fogref import params
from fogref.atomic import check_output_file, is_stream, refuse_overwriting_inputs
from fogref.cli.checks import Assignments, Check, Integer, PathArg, Text
from fogref.errors import FogrefError, did_you_mean

__all__ = [
    "Parser",
    "UsageError",
    "add_options",
    "api_arguments",
    "assignments",
    "check_paths",
    "option",
    "parse_options",
    "processes_option",
    "refuse",
    "switch",
    "toggle",
]


class UsageError(FogrefError):
    """A command line that argparse or an option check refused (exit 2, one line)."""


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors raise :class:`UsageError` instead of printing
    the usage and exiting, so that fogref's ``main`` prints them as one line."""

    def error(self, message):
        raise UsageError(f"{self.prog}: {_suggest(self, message)} (see {self.prog} --help)")


def _suggest(parser: argparse.ArgumentParser, message: str) -> str:
    """argparse's ``unrecognized arguments: --from-scne`` with a did-you-mean for each unknown option.

    >>> p = Parser(prog="demo")
    >>> _ = p.add_argument("--from-scene", action="store_true")
    >>> _suggest(p, "unrecognized arguments: --from-scne x")
    "unrecognized arguments: --from-scne x; did you mean '--from-scene'?"
    """
    head = "unrecognized arguments: "
    if not message.startswith(head):
        return message
    flags, todo = [], [parser]
    while todo:  # this parser's options and its subcommands'
        for a in todo.pop()._actions:
            flags += a.option_strings
            if isinstance(a, argparse._SubParsersAction):
                todo += list(a.choices.values())
    for word in message[len(head) :].split():
        if word.startswith("--"):
            hint = did_you_mean(word.partition("=")[0], flags)
            if hint:
                return message + hint
    return message


# --------------------------------------------------------------------------- fields


#: An option's metadata, each key's value when not given (see :func:`option`).
_BLANK = {
    "help": "",
    "check": None,
    "flag": None,
    "short": None,
    "metavar": None,
    "positional": False,
    "repeat": False,
    "nargs": None,
    "group": None,
    "api": None,
    "api_name": None,
    "default_text": None,
    "switch": False,
    "negates": False,
    "toggle": False,
}


def option(
    default=MISSING,
    help: str = "",
    *,
    check: Check | None = None,
    flag: str | None = None,
    short: str | None = None,
    metavar: str | None = None,
    positional: bool = False,
    repeat: bool = False,
    nargs: int | str | None = None,
    group: str | None = None,
    api: str | None = None,
    api_name: str | None = None,
    default_text: str | None = None,
):
    """A dataclass field that is a command-line option.

    Parameters
    ----------
    default : the value when the option is not given; omitted: the option is required.
    help : what the option is, for users; the range (from ``check``) and the default are appended.
    check : converts and validates the text (default: :class:`Text`).
    flag, short : the option's name (default ``--<field-name>``) and a short alias.
    positional : an argument without a flag (``nargs="?"`` when it has a default).
    repeat : may be given several times; the check gets the list (default: each item checked).
    nargs : a fixed count of words (``--sun-dir X Y Z``).
    group : the help section.
    api, api_name : ``"module:function"`` whose parameter ``api_name`` (default: the field's name)
        has the same default (checked by tests/test_cli_spec.py).
    default_text : how the default is shown in the help (default: the value; None: not shown).
    """
    return _field(default, dict(locals(), check=check or Text()))


def assignments(help: str, **kw):
    """A repeatable ``NAME=VALUE`` option (:class:`~fogref.cli.checks.Assignments`), None unless given;
    ``kw`` as :func:`option`'s."""
    return option(None, help, repeat=True, check=Assignments(), **kw)


def _field(default, given: dict) -> dataclasses.Field:
    """A dataclass field holding an option's metadata: :data:`_BLANK`, the keys of ``given`` overriding."""
    md = {"fogref": {k: given.get(k, blank) for k, blank in _BLANK.items()}}
    return field(metadata=md) if default is MISSING else field(default=default, metadata=md)


def processes_option(figures: str):
    """The ``--processes N`` option of a command that draws ``figures`` on worker processes
    (:mod:`fogref.compare.workers`): default None, one per core the process may use, where the
    Python API's default is 1 (a worker imports the caller's main module)."""
    return option(
        None,
        f"worker processes that draw {figures}",
        check=Integer(1, 1024),
        metavar="N",
        default_text="one per core this process may use; the Python API's default is 1",
    )


def switch(
    help: str = "",
    *,
    flag: str | None = None,
    group: str | None = None,
    api: str | None = None,
    api_name: str | None = None,
    negates: bool = False,
):
    """A boolean flag, False unless given.  ``negates``: the API parameter ``api_name`` is its
    opposite (``--no-png`` is ``png=False``)."""
    return _field(False, dict(locals(), switch=True))


def toggle(
    help: str = "",
    *,
    flag: str | None = None,
    group: str | None = None,
    api: str | None = None,
    api_name: str | None = None,
    default_text: str | None = None,
):
    """A ``--x``/``--no-x`` pair: True, False, or None when neither is given (given once at most)."""
    return _field(None, dict(locals(), toggle=True))


def meta(f: dataclasses.Field) -> dict:
    return f.metadata["fogref"]


def flag_of(f: dataclasses.Field) -> str:
    """The option's name on the command line (``--spp``), or the positional's name."""
    m = meta(f)
    if m["positional"]:
        return m["metavar"] or f.name.upper()
    return m["flag"] or "--" + f.name.replace("_", "-")


def _shown(value) -> str:
    if isinstance(value, (tuple, list)):
        return ",".join(_shown(v) for v in value)
    if isinstance(value, float):
        return params.format_number(value)
    return str(value)


def help_text(f: dataclasses.Field) -> str:
    """The option's help line: its text, its range and unit, its default."""
    m = meta(f)
    parts = [m["help"]]
    rng = m["check"].describe() if m["check"] is not None else ""
    if m["toggle"] and m["default_text"]:
        return (m["help"] + f" (default: {m['default_text']})").replace("%", "%%")
    if rng:
        parts.append(rng)
    text = "; ".join(p for p in parts if p)
    shown = m["default_text"]
    if shown is None and f.default is not MISSING and f.default is not None and not m["switch"]:
        shown = _shown(f.default)
    if shown:
        text += f" (default {shown})"
    if m["repeat"]:
        text += "; repeatable"
    return text.replace("%", "%%")


class _Once(argparse.Action):
    """Store an option's value; refuse it given a second time (the parser's defaults are
    suppressed, so an option already in the namespace was given before)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if hasattr(namespace, self.dest):
            raise argparse.ArgumentError(
                self, f"given twice ({getattr(namespace, self.dest)!r} and {values!r}); give it once"
            )
        setattr(namespace, self.dest, values)


class _OnceToggle(argparse.BooleanOptionalAction):
    """``--x``/``--no-x``, refused when given twice (either spelling)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if hasattr(namespace, self.dest):
            raise argparse.ArgumentError(
                self, "given twice; give --x or --no-x once".replace("x", self.option_strings[0][2:])
            )
        super().__call__(parser, namespace, values, option_string)


class _OnceTrue(_Once):
    def __init__(self, option_strings, dest, **kw):
        super().__init__(option_strings, dest, nargs=0, **kw)

    def __call__(self, parser, namespace, values, option_string=None):
        super().__call__(parser, namespace, True, option_string)


def add_options(parser: argparse.ArgumentParser, spec) -> None:
    """Add every field of the dataclass ``spec`` to ``parser`` (its defaults suppressed:
    :func:`parse_options` fills them from the dataclass)."""
    groups: dict[str, argparse._ArgumentGroup] = {}
    for f in dataclasses.fields(spec):
        m = meta(f)
        where = parser
        if m["group"]:
            where = groups.get(m["group"]) or groups.setdefault(
                m["group"], parser.add_argument_group(m["group"])
            )
        kw = {"help": help_text(f), "default": argparse.SUPPRESS}
        if m["switch"] or m["toggle"]:
            where.add_argument(
                flag_of(f), dest=f.name, action=_OnceToggle if m["toggle"] else _OnceTrue, **kw
            )
            continue
        metavar = m["metavar"] or m["check"].metavar
        if m["nargs"] is not None:
            kw["nargs"] = m["nargs"]
        if m["positional"]:
            if f.default is not MISSING:
                kw["nargs"] = "?"
            where.add_argument(f.name, metavar=metavar or f.name.upper(), **kw)
            continue
        names = [flag_of(f)] + ([m["short"]] if m["short"] else [])
        if metavar:
            kw["metavar"] = metavar
        if f.default is MISSING:
            kw["required"] = True
        where.add_argument(*names, dest=f.name, action="append" if m["repeat"] else _Once, **kw)


def parse_options(ns: argparse.Namespace, spec, source: str):
    """The ``spec`` dataclass of a parsed namespace, each given value converted by its check,
    and the set of field names the user gave.  ParameterError (naming the option) for a
    value its check refuses."""
    values, given = {}, set()
    for f in dataclasses.fields(spec):
        if not hasattr(ns, f.name):
            continue
        given.add(f.name)
        m, raw = meta(f), getattr(ns, f.name)
        if m["switch"]:
            values[f.name] = True
        elif m["toggle"]:
            values[f.name] = bool(raw)
        elif m["repeat"] and not m["check"].takes_list:
            values[f.name] = tuple(m["check"].parse(r, flag_of(f), source) for r in raw)
        elif raw is None and m["positional"]:
            continue
        else:
            values[f.name] = m["check"].parse(raw, flag_of(f), source)
    return spec(**values), given


def refuse(spec, given: set, these, those, source: str, why: str = "") -> None:
    """UsageError if an option of ``these`` is given together with one of ``those`` (field names
    of the dataclass ``spec``): options that do not apply to the chosen mode are refused.

    >>> from dataclasses import dataclass
    >>> @dataclass
    ... class Demo:
    ...     image: str = option(None, "an image")
    ...     precision: str = option("float32", "precision")
    >>> refuse(Demo, {"image", "precision"}, ["image"], ["precision"], "demo", "a model's option")
    Traceback (most recent call last):
    ...
    fogref.cli.spec.UsageError: demo: --precision does not apply with --image (a model's option)
    """
    fields = {f.name: f for f in dataclasses.fields(spec)}
    a = [flag_of(fields[n]) for n in these if n in given]
    b = [flag_of(fields[n]) for n in those if n in given]
    if a and b:
        raise UsageError(
            f"{source}: {', '.join(b)} does not apply with {', '.join(a)}" + (f" ({why})" if why else "")
        )


def api_arguments(opts, api: str) -> dict:
    """The keyword arguments of the Python function ``api`` (``"module:function"``) from the options
    of ``opts`` declared with it: each value under its ``api_name`` (default: the field's name),
    the opposite for a ``negates`` switch (``--no-png`` is ``png=False``).

    >>> from dataclasses import dataclass
    >>> @dataclass
    ... class Demo:
    ...     spp: int = option(64, "samples per pixel", api="m:f")
    ...     no_png: bool = switch("no PNG", api="m:f", api_name="png", negates=True)
    ...     quiet: bool = switch("no progress bar")
    >>> api_arguments(Demo(spp=8), "m:f")
    {'spp': 8, 'png': True}
    """
    out = {}
    for f in dataclasses.fields(opts):
        m, value = meta(f), getattr(opts, f.name)
        if m["api"] == api:
            out[m["api_name"] or f.name] = not value if m["negates"] else value
    return out


def _paths(opts, role: str) -> list[tuple[str, str]]:
    """``(flag, path)`` of every option of ``opts`` whose check has the ``role`` ("input", "output")."""
    out = []
    for f in dataclasses.fields(opts):
        chk, value = meta(f)["check"], getattr(opts, f.name)
        r = getattr(chk, "role", "")
        if isinstance(chk, PathArg) and chk.must_exist and chk.kind == "file":
            r = r or "input"
        if r != role or value is None:
            continue
        for v in value if isinstance(value, (tuple, list)) else (value,):
            out.append((flag_of(f), str(v)))
    return out


def check_paths(opts, source: str) -> None:
    """Before any work: a one-line error if an output file option of ``opts`` (``PathArg(role=
    "output")``: ``--json``, ``--junit``, ``--out S.xml``...) is a folder, or would overwrite an
    input file option (``PathArg(role="input")``: the truth, the images, the scene), or another
    output (:func:`fogref.atomic.refuse_overwriting_inputs`, the one check of every command)."""
    outputs = _paths(opts, "output")
    for flag, p in outputs:
        check_output_file(p, f"{source}: {flag}")
    inputs = [(q, f"input {n}") for n, q in _paths(opts, "input")]
    for i, (flag, p) in enumerate(outputs):
        refuse_overwriting_inputs([(p, "output")], inputs, f"{source}: {flag}")
        for other, q in outputs[:i]:
            if not is_stream(p) and os.path.realpath(p) == os.path.realpath(q):
                raise UsageError(f"{source}: {flag} and {other} name the same file {p}; give two files")

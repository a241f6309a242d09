"""fogref's command line: ``fogref <command> [options]``, one module per command.

==========  =================================================================  =====================
command     what it does                                                       module
==========  =================================================================  =====================
render      path-trace a scene to a ground-truth EXR (+ PNG preview)           :mod:`~.render`
info        channels, parameters, spp, seed and noise level of an EXR          :mod:`~.info`
compare     check a fog model or an engine's images against a truth; exit      :mod:`~.compare`
            0 pass, 1 fail, 2 usage or input error, 3 inconclusive
diff        two truths or images: equal within noise? exit 0 equal, 1 differ   :mod:`~.diff`
study       the Unreal study: fit, compare, error budget, README               :mod:`~.study`
fit         fit Unreal's fog colours and exponent to a physical fog (JSON)     :mod:`~.fit`
translate   carry one engine's fog settings to another's through the truth     :mod:`~.translate`
export      paste-ready fog, camera and sun for an engine (UE Python, .tres)   :mod:`~.export`
scene       write a scene XML from fog, sun, sky, camera and geometry          :mod:`~.scene`
sweep       run a declarative error study (SWEEP.toml) on Dask                 :mod:`~.sweep`
engine      render a truth's view with a real web engine (Chromium)            :mod:`~.engine`
==========  =================================================================  =====================

Each command's options are declared once, as the dataclass ``Options`` of its module
(:mod:`fogref.cli.spec`): default, check (:mod:`fogref.params`), unit, range and help.
Errors meant for the user (:class:`fogref.errors.FogrefError`, bad options included)
print as one line ``fogref: error: ...`` and exit with 2; Ctrl-C exits with 130.
``fogref render`` builds only its own parser, so it imports no other command's modules.

Examples
--------
>>> module, opts, given = parse(["render", "scenes/valley.xml", "--out", "out/v.exr", "--set", "res=64"])
>>> module.NAME, opts.spp, opts.seed, opts.overrides, sorted(given)
('render', 64, 0, {'res': '64'}, ['out', 'overrides', 'scene'])
>>> sorted(build_parser()._subparsers._group_actions[0].choices) == sorted(COMMANDS)
True
"""

from __future__ import annotations

import gc
import importlib
import os
import sys

from fogref._version import __version__
from fogref.cli.spec import Parser, UsageError, add_options, check_paths, parse_options
from fogref.errors import FogrefError, did_you_mean

__all__ = ["COMMANDS", "build_parser", "main", "parse"]

#: The commands, in the order ``fogref --help`` lists them, and the module of each.
_NAMES = "render info compare diff study fit translate export scene sweep engine"
COMMANDS = {name: f"fogref.cli.{name}" for name in _NAMES.split()}

DESCRIPTION = (
    "fogref: path-traced ground truth for game-engine fog (Mitsuba 3), and the tools that check "
    "an engine's fog against it.  `fogref COMMAND --help` gives each command's options, "
    "their units, ranges and defaults."
)
EPILOG = (
    "exit codes: 0 success (compare: pass), 1 compare: fail, 2 usage or input error (one line "
    "'fogref: error: ...'), 3 compare: inconclusive, 130 interrupted (a render resumes when run again)"
)


def _module(name: str):
    return importlib.import_module(COMMANDS[name])


def build_parser(only: str | None = None) -> Parser:
    """fogref's argument parser; ``only``: with that command alone (what :func:`main` builds, so
    that ``fogref render`` imports none of the other commands' modules).

    >>> sorted(build_parser(only="render")._subparsers._group_actions[0].choices)
    ['render']
    """
    p = Parser(prog="fogref", description=DESCRIPTION, epilog=EPILOG)
    p.add_argument("--version", action="version", version=f"fogref {__version__}")
    sub = p.add_subparsers(dest="cmd", required=True, metavar="COMMAND", title="commands")
    for name in COMMANDS if only is None else (only,):
        m = _module(name)
        sp = sub.add_parser(name, help=m.HELP, description=m.DESCRIPTION, epilog=getattr(m, "EPILOG", None))
        add_options(sp, m.Options)
    return p


def _command(argv) -> str | None:
    """The command named by ``argv`` (its first word that is not an option), or None.

    >>> _command(["render", "s.xml"]), _command(["--version"]), _command([])
    ('render', None, None)
    """
    return next((a for a in argv if not a.startswith("-")), None)


def parse(argv):
    """``(command module, its Options, the names of the options given)`` for ``argv``.

    Raises :class:`~fogref.cli.spec.UsageError` / ParameterError (FogrefError) for a bad
    command line; ``--help`` and ``--version`` print and raise SystemExit(0) as argparse does.
    """
    argv = list(argv)
    cmd = _command(argv)
    if cmd is not None and cmd not in COMMANDS:
        raise UsageError(
            f"fogref: unknown command '{cmd}'{did_you_mean(cmd, COMMANDS)} "
            f"(one of {', '.join(COMMANDS)}; see fogref --help)"
        )
    ns = build_parser(only=cmd).parse_args(argv)
    module = _module(ns.cmd)
    opts, given = parse_options(ns, module.Options, f"fogref {ns.cmd}")
    return module, opts, given


def main(argv=None) -> int:
    """Run the command ``argv`` (default: this process's command line, ``sys.argv[1:]``); returns
    the exit code.

    Called without ``argv`` (the ``fogref`` script, ``python -m fogref.cli``) the process ends
    with this call: the objects it made are then frozen out of the garbage collector
    (``gc.freeze``), so that the interpreter's exit does not walk every object of Mitsuba,
    Dr.Jit and numpy once more.  Files are all written and closed by then; ``main([...])`` in
    a longer-lived process leaves the collector alone.
    """
    ends_process = argv is None
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        return _run(argv)
    finally:
        if ends_process:
            gc.freeze()


def _run(argv) -> int:
    try:
        module, opts, given = parse(argv)
        check_paths(opts, f"fogref {module.NAME}")
        return module.run(opts, given)
    except FogrefError as e:
        print(f"fogref: error: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # `fogref ... | head`: the reader left; not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt as e:  # a sweep's SweepInterrupted names the workers' log
        print(
            f"fogref: {e}" if str(e) else "fogref: interrupted; run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    except OSError as e:  # a full disk, a vanished folder, permissions: the file and the reason
        where = f"{e.filename}: " if e.filename else ""
        print(f"fogref: error: {where}{e.strerror or e}", file=sys.stderr)
        return 2

"""fogref's command line: ``fogref render``, ``fogref compare``, ``fogref study``, ``fogref fit``.

``render`` is defined here; :mod:`fogref.compare` and :mod:`fogref.study` add
their subcommands through their ``add_cli(subparsers)``. Errors meant for the
user (:class:`fogref.errors.FogrefError`) print as one line and exit with 2.

Examples
--------
>>> p = build_parser()
>>> a = p.parse_args(["render", "scenes/valley.xml", "--out", "out/v.exr", "--set", "res=64"])
>>> a.cmd, a.spp, a.seed, _kv(a.set)
('render', 64, 0, {'res': '64'})
>>> {"render", "compare", "study", "fit"} <= set(p._subparsers._group_actions[0].choices)
True
"""

from __future__ import annotations

import argparse
import sys

from fogref.errors import FogrefError


def _kv(items) -> dict[str, str]:
    """``["NAME=VALUE", ...]`` (the ``--set`` options) as a dict of strings.

    >>> _kv(["res=64", "title=a=b"])
    {'res': '64', 'title': 'a=b'}
    >>> _kv(None)
    {}
    """
    out = {}
    for it in items or []:
        if "=" not in it:
            raise FogrefError(f"--set: expected NAME=VALUE, got '{it}'")
        k, v = it.split("=", 1)
        out[k] = v
    return out


def cmd_render(a) -> int:
    from fogref.render.render import render

    path = render(a.scene, a.out, spp=a.spp, seed=a.seed, variant=a.variant, overrides=_kv(a.set),
                  progress=not a.quiet, resume=not a.no_resume, png=not a.no_png, pixel_filter=a.pixel_filter,
                  checkpoint_seconds=a.checkpoint_seconds)
    print(path)
    return 0


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """fogref's argument parser.  ``only="render"``: the ``render`` subcommand alone (what
    :func:`main` builds for ``fogref render ...``, so that it imports none of the other
    subcommands' modules: they are imported only to build their own parsers).

    >>> sorted(build_parser(only="render")._subparsers._group_actions[0].choices)
    ['render']
    """
    p = argparse.ArgumentParser(prog="fogref", description=__doc__)
    from fogref._version import __version__

    p.add_argument("--version", action="version", version=f"fogref {__version__}")
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render", help="path-trace a scene to a ground-truth EXR (+ PNG preview)")
    r.add_argument("scene", help="Mitsuba XML scene using heightfog + fogpath")
    r.add_argument("--spp", type=int, default=64, help="samples per pixel (default 64)")
    r.add_argument("--seed", type=int, default=0, help="random seed (same seed, same pixels)")
    r.add_argument("-o", "--out", required=True, help="output EXR path")
    r.add_argument("--variant", default=None, help="Mitsuba variant (default llvm_ad_rgb; cuda_ad_rgb on a GPU)")
    r.add_argument("--set", action="append", metavar="NAME=VALUE", help="override an XML $default")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--no-resume", action="store_true", help="ignore a checkpoint of an interrupted run")
    r.add_argument("--no-png", action="store_true", help="no PNG preview beside the EXR")
    r.add_argument("--pixel-filter", choices=("centre", "box"), default="centre",
                   help="centre: every sample through the pixel centre, exact G-buffer and T (default, for "
                   "truths); box: samples spread over the pixel (anti-aliased pictures)")
    r.add_argument("--checkpoint-seconds", type=float, default=60.0, metavar="S",
                   help="seconds between checkpoints of an interruptible render (default 60; also on Ctrl-C)")
    r.set_defaults(func=cmd_render)
    if only == "render":
        return p
    # each subcommand package adds its own parser; an import error here is a bug and is raised
    from fogref.compare import add_cli as add_compare_cli
    from fogref.info import add_cli as add_info_cli
    from fogref.render.scene_writer import add_cli as add_scene_cli
    from fogref.study import add_cli as add_study_cli
    from fogref.study.sweep import add_cli as add_sweep_cli

    add_compare_cli(sub)
    add_study_cli(sub)
    add_sweep_cli(sub)
    add_info_cli(sub)
    add_scene_cli(sub)
    return p


def _command(argv) -> str | None:
    """The subcommand named by ``argv`` (its first word that is not an option), or None.

    >>> _command(["render", "s.xml"]), _command(["--version"]), _command([])
    ('render', None, None)
    """
    return next((a for a in argv if not a.startswith("-")), None)


def main(argv=None) -> int:
    """Run the command ``argv`` (default: this process's command line, ``sys.argv[1:]``).

    Called without ``argv`` (the ``fogref`` script, ``python -m fogref.cli``) the process ends
    with this call: the objects it made are then frozen out of the garbage collector
    (``gc.freeze``), so that the interpreter's exit does not walk every object of Mitsuba,
    Dr.Jit and numpy once more (~40 ms of a ~50 ms exit).  Files are all written and closed
    by then; ``main([...])`` in a longer-lived process leaves the collector alone.
    """
    ends_process = argv is None
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        return _run(argv)
    finally:
        if ends_process:
            import gc

            gc.freeze()


def _run(argv) -> int:
    args = build_parser(only="render" if _command(argv) == "render" else None).parse_args(argv)
    try:
        return args.func(args)
    except FogrefError as e:
        print(f"fogref: error: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # `fogref ... | head`: the reader left; not an error
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print("fogref: interrupted; run the same command again to resume", file=sys.stderr)
        return 130
    except OSError as e:  # a full disk, a vanished folder, permissions: the file and the reason
        where = f"{e.filename}: " if e.filename else ""
        print(f"fogref: error: {where}{e.strerror or e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

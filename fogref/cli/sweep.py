"""``fogref sweep SWEEP.toml``: a declarative error study over many configurations, on Dask.

The work is :func:`fogref.study.sweep.run_sweep` (the file's format is described there);
its defaults are the options' defaults.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fogref.cli.checks import Address, Integer, PathArg
from fogref.cli.spec import api_arguments, option, refuse, switch
from fogref.html.reports import write_sweep_html
from fogref.study.sweep import run_sweep

NAME = "sweep"
SOURCE = "fogref sweep"
HELP = "run a declarative error study (SWEEP.toml) on Dask"
DESCRIPTION = (
    "Run a declarative error study: the scenes, the parameters to vary, the design, the models and "
    "the outputs are in a TOML file (see fogref.study.sweep).  Each configuration renders its truth "
    "(or reuses it from the cache) and compares every model; one table of rows, plots beside it.  "
    "An interrupted sweep resumes."
)
EPILOG = (
    "exit codes: 0 finished (failed configurations are rows with status 'error'), 2 usage or input error, "
    "130 interrupted (run again to resume)"
)
RUN = "fogref.study.sweep:run_sweep"


@dataclass
class Options:
    sweep: str = option(
        help="the sweep file (TOML)", positional=True, check=PathArg(role="input"), metavar="SWEEP.toml"
    )
    scheduler: str | None = option(
        None,
        "a running Dask scheduler (tcp://HOST:8786)",
        check=Address(),
        metavar="ADDRESS",
        api=RUN,
        default_text="a LocalCluster on this machine",
    )
    workers: int | None = option(
        None,
        "LocalCluster worker processes",
        check=Integer(1, 4096),
        api=RUN,
        api_name="n_workers",
        default_text="one per core",
    )
    drjit_threads: int | None = option(
        None,
        "Dr.Jit threads per worker",
        check=Integer(1, 4096),
        api=RUN,
        default_text="cores / workers on a LocalCluster",
    )
    retry_failed: bool = switch("re-run configurations recorded as failed", api=RUN)
    quiet: bool = switch("no progress bar", api=RUN, api_name="progress", negates=True)


def run(a: Options, given=frozenset()) -> int:
    """Run the sweep; print a one-line summary."""
    refuse(
        Options, given, ("scheduler",), ("workers",), SOURCE, "the workers of a running scheduler are its own"
    )
    info = run_sweep(a.sweep, **api_arguments(a, RUN))
    print(
        f"{info['configs']} configurations ({info['ran']} run now, {info['failed']} failed) in "
        f"{info['wall_seconds']:.1f} s; table: {info['table']} ({info['rows']} rows), {info['parquet']}; "
        f"{len(info['plots'])} plots"
    )

    print(f"html: {write_sweep_html(Path(info['table']).parent, Path(info['table']).stem)}")
    return 0

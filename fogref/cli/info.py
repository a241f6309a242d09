"""``fogref info EXR``: channels, parameters, spp, seed and noise level of an EXR (:mod:`fogref.info`)."""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

from fogref.cli.checks import PathArg
from fogref.cli.spec import option, switch
from fogref.info import describe, info

NAME = "info"
HELP = "channels, parameters, spp, seed and noise level of an EXR"
DESCRIPTION = (
    "Describe an EXR: its channels, and for a fogref ground truth the scene, parameters, spp, seed, "
    "noise level and camera."
)
EPILOG = "exit codes: 0 described, 2 usage or input error"


@dataclass
class Options:
    exr: str = option(
        help="a ground-truth EXR (or any EXR)", positional=True, check=PathArg(role="input"), metavar="EXR"
    )
    json: bool = switch("print everything as one JSON object (camera included)")


def run(o: Options, given=frozenset()) -> int:
    """Print :func:`fogref.info.describe`, or with ``--json`` :func:`fogref.info.info` as JSON
    (a reader that closes the pipe, ``fogref info x.exr | head``, is no error: :func:`fogref.cli.main`)."""
    print(json.dumps(info(Path(o.exr)), indent=2, default=float) if o.json else describe(Path(o.exr)))
    sys.stdout.flush()
    return 0

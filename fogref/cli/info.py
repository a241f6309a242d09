"""``fogref info EXR``: channels, parameters, spp, seed and noise level of an EXR (:mod:`fogref.info`)."""

from __future__ import annotations

from dataclasses import dataclass

from fogref.cli.spec import PathArg, option, switch

NAME = "info"
HELP = "channels, parameters, spp, seed and noise level of an EXR"
DESCRIPTION = ("Describe an EXR: its channels, and for a fogref ground truth the scene, parameters, spp, seed, "
               "noise level and camera.")
EPILOG = "exit codes: 0 described, 2 usage or input error"


@dataclass
class Options:
    exr: str = option(help="a ground-truth EXR (or any EXR)", positional=True, check=PathArg(), metavar="EXR")
    json: bool = switch("print everything as one JSON object (camera included)")


def run(o: Options, given=frozenset()) -> int:
    from fogref.info import run_info_command

    return run_info_command(o)

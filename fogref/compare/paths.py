"""No output over an input: the one check that a file fogref compare/check writes does not
replace a file it reads (the truth, an engine's image) or another output.

Paths are compared resolved (:func:`os.path.realpath`: symlinks, ``..`` and relative paths
included), before any work is done.
"""

from __future__ import annotations

import os

from fogref.errors import ParameterError

__all__ = ["refuse_output_over_input"]


def refuse_output_over_input(outputs, inputs, source: str = "compare", what: str = "input") -> None:
    """ParameterError if an output would replace an input: paths compared resolved
    (:func:`os.path.realpath`: symlinks, ``..`` and relative paths included).

    ``outputs``: ``(option, path)`` pairs; ``inputs``: ``(option, path)`` pairs (None skipped).

    >>> refuse_output_over_input([("--out", "r/errors.exr")], [("EXR", "r/../r/errors.exr")])
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: compare: parameter '--out': it would write r/errors.exr over ...
    """
    given = {}
    for name, p in inputs:
        if p is not None:
            given.setdefault(os.path.realpath(os.fspath(p)), (name, p))
    for name, p in outputs:
        hit = given.get(os.path.realpath(os.fspath(p)))
        if hit is not None:
            raise ParameterError(
                source,
                name,
                f"it would write {p} over the {what} {hit[0]} ({hit[1]}); "
                f"choose another output path or rename the {what}",
            )

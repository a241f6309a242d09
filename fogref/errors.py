"""Errors that name the file, the parameter and the allowed range.

:class:`FogrefError` is what the command line prints as one line (exit status
2); everything else is a bug and keeps its traceback. This module imports no
other fogref module, so every layer may raise these.

Examples
--------
>>> e = ParameterError("scenes/valley.xml: medium 'fog'", "falloff", "-1.0 must be >= 0 [1/m]")
>>> str(e)
"scenes/valley.xml: medium 'fog': parameter 'falloff': -1.0 must be >= 0 [1/m]"
>>> isinstance(e, FogrefError) and isinstance(e, ValueError), e.name
(True, 'falloff')
"""

import difflib


def did_you_mean(word: str, options) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``options`` to ``word``, else ``""``.

    >>> did_you_mean("skyy", ["all", "surface", "sky"])
    "; did you mean 'sky'?"
    >>> did_you_mean("zzz", ["sky"])
    ''
    """
    close = difflib.get_close_matches(str(word), list(options), n=1)
    return f"; did you mean '{close[0]}'?" if close else ""


class FogrefError(Exception):
    """Base class of fogref's user-facing errors."""


class ParameterError(FogrefError, ValueError):
    """A parameter is out of range or malformed.

    ``source`` is the file (or object) that held it, ``name`` the parameter.
    """

    def __init__(self, source: str, name: str, message: str):
        self.source, self.name = source, name
        super().__init__(f"{source}: parameter '{name}': {message}")

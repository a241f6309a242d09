"""Errors that name the file, the parameter and the allowed range."""


class FogrefError(Exception):
    """Base class of fogref's user-facing errors."""


class ParameterError(FogrefError, ValueError):
    """A parameter is out of range or malformed.

    ``source`` is the file (or object) that held it, ``name`` the parameter.
    """

    def __init__(self, source: str, name: str, message: str):
        self.source, self.name = source, name
        super().__init__(f"{source}: parameter '{name}': {message}")

"""fogref's version (one place: the package, the EXR header's ``fogref.version``)."""

__version__ = "0.2.0"

"""Package list for setuptools: everything else is in pyproject.toml.

``fogref`` and each of its sub-packages are found; ``plugins/`` installs as ``fogref_plugins``
(``package-dir`` in pyproject.toml). A ``[tool.setuptools.packages.find]`` table cannot rename a
folder, hence this file.
"""

from setuptools import find_packages, setup

setup(packages=[*find_packages(include=["fogref", "fogref.*"]), "fogref_plugins"])

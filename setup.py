"""Package list for setuptools: everything else is in pyproject.toml.

``fogref`` and each of its sub-packages are found; ``plugins/`` installs as ``fogref_plugins``
(``package-dir`` in pyproject.toml). A ``[tool.setuptools.packages.find]`` table cannot rename a
folder, hence this file.
"""

from setuptools import find_packages, setup

# fogref/scenes holds data only (no __init__.py): named here so that its XML files install
setup(packages=[*find_packages(include=["fogref", "fogref.*"]), "fogref.scenes", "fogref_plugins"])

"""pytest set-up shared by tests/ and the doctests in fogref/ (``--doctest-modules``).

colour-science calls ``numpy.set_printoptions(legacy="1.13")`` when imported, so
an array's repr in a docstring example would depend on whether an earlier module
imported colour. Every doctest runs under numpy's default print options instead.
"""

import numpy as np
import pytest


@pytest.fixture(autouse=True)
def _numpy_default_printoptions(request):
    if isinstance(request.node, pytest.DoctestItem):
        with np.printoptions(legacy=False, sign="-"):
            yield
    else:
        yield

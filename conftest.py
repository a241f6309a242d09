"""pytest set-up shared by tests/ and the doctests in fogref/ (``--doctest-modules``).

A test or doctest that renders with Mitsuba without the ``render`` marker fails
(:func:`pytest_runtest_call`), so that ``-m "not render"`` is the fast tier.

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


# ---------------------------------------------------------------- the render marker, enforced
#: What the running test rendered: fogpath's ``render``/``render_moments`` and ``mi.render`` (any
#: integrator), counted once Mitsuba is set up (fogref_plugins.register runs in set_variant).
_RENDERS: list[str] = []


def _counting(cls, name: str) -> None:
    original = getattr(cls, name)

    def counted(*args, **kwargs):
        _RENDERS.append(f"{cls.__name__}.{name}")
        return original(*args, **kwargs)

    setattr(cls, name, counted)


def _count_renders_once_mitsuba_is_set_up() -> None:
    import fogref_plugins

    register = fogref_plugins.register

    def register_and_count() -> None:
        register()
        from fogref_plugins.fogpath import FogPathIntegrator
        from mitsuba.python import util

        if not getattr(FogPathIntegrator, "_fogref_counted", False):
            _counting(FogPathIntegrator, "render")
            _counting(FogPathIntegrator, "render_moments")
            _counting(util._RenderOp, "eval")
            FogPathIntegrator._fogref_counted = True

    fogref_plugins.register = register_and_count


_count_renders_once_mitsuba_is_set_up()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    """A test (or doctest) that renders with Mitsuba must carry the ``render`` marker, so that
    ``-m "not render"`` leaves every render out."""
    _RENDERS.clear()
    result = yield
    if _RENDERS and item.get_closest_marker("render") is None:
        pytest.fail(
            f"{item.nodeid} renders ({', '.join(sorted(set(_RENDERS)))}) without @pytest.mark.render",
            pytrace=False,
        )
    return result

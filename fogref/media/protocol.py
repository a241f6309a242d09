"""The height-profile protocol, its registry, and the parameter parsers it uses.

A *height profile* is the relative density ``rho(y)`` of one fog layer as a
function of height only (y-up, metres).  Modelled on pbrt-v4's density providers
(``src/pbrt/media.h``: ``HomogeneousMedium``, ``GridMedium``'s
``DensityGrid``/``MajorantGrid`` queries, ``IsEmptyInterval``), every profile
answers the same questions, so the medium, the closed-form single scattering and
the Mitsuba plugin ask instead of sniffing attributes:

==================================  ============================================
``validate(src, i)``                raise :class:`~fogref.errors.ParameterError`
                                    naming ``layer{i}.<field>`` on a bad value
``rho(ops, y)``                     relative density at height ``y`` (>= 0)
``depth(ops, oy, dy, t)``           shape optical depth [m] over ``[0, t]``
``sample(ops, oy, dy, s)``          the distance where ``depth`` reaches ``s``
``max_density(ops, y_lo, y_hi)``    largest ``rho`` on ``[y_lo, y_hi]``
``is_constant``                     ``rho`` does not depend on height
``is_empty``                        ``rho`` is 0 everywhere
``reference_height``                the profile's characteristic height [m]
``from_params(params, src)``        the layers of a flat parameter dict
==================================  ============================================

The registry maps the ``heightfog`` XML ``profile`` names to a parser
(``from_params``-like callable) and says whether the profile needs a box.  A new
profile is one file: its class, and a :func:`register_profile` call next to it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, ClassVar, Protocol, runtime_checkable

from fogref import params

__all__ = [
    "HeightProfile",
    "ProfileEntry",
    "PROFILES",
    "NonIncreasingLayer",
    "register_profile",
    "profile_entry",
    "number",
    "rgb",
]


@runtime_checkable
class HeightProfile(Protocol):
    """One layer's relative density as a function of height (see the module doc).

    ``ops`` is an array back end (:data:`fogref.media.NP` or
    :func:`fogref.media.drjit_ops`); heights ``y``, ``oy`` are metres; ``dy`` is
    the y component of a unit ray direction; ``t`` a distance [m] along the ray
    (``ops.largest``: to infinity); ``s`` a shape optical depth [m].  Depths
    saturate at :data:`fogref.media.closed_form.TAU_MAX`; ``sample`` returns
    ``ops.largest`` when the ray escapes before reaching ``s``.
    """

    #: the XML profile name the class is registered under.
    profile: ClassVar[str]

    def validate(self, src: str, i: int) -> None: ...

    def rho(self, ops: Any, y: Any) -> Any: ...

    def depth(self, ops: Any, oy: Any, dy: Any, t: Any) -> Any: ...

    def sample(self, ops: Any, oy: Any, dy: Any, s: Any) -> Any: ...

    def max_density(self, ops: Any, y_lo: Any, y_hi: Any) -> Any: ...

    @property
    def is_constant(self) -> bool: ...

    @property
    def is_empty(self) -> bool: ...

    @property
    def reference_height(self) -> float: ...


class NonIncreasingLayer:
    """The members shared by the layers whose ``rho`` is ``density`` [1/m] times a shape that never
    increases with height (:class:`~fogref.media.ExpLayer`, :class:`~fogref.media.HDRPLayer`,
    :class:`~fogref.media.PowerLawLayer`, :class:`~fogref.media.UEPathTracerLayer`).

    A mixin for a frozen dataclass with a ``density`` field (>= 0) and a ``rho(ops, y)`` method:
    the layer is empty when ``density <= 0``, and the largest ``rho`` on ``[y_lo, y_hi]`` is
    ``rho(y_lo)``.

    Examples
    --------
    >>> from fogref.media import NP, ExpLayer
    >>> ExpLayer(0.0, 0.1, 0.0).is_empty, ExpLayer(0.5, 0.1, 0.0).is_empty
    (True, False)
    >>> float(ExpLayer(0.5, 0.1, 0.0).max_density(NP, 0.0, 10.0))
    0.5
    """

    density: float

    if TYPE_CHECKING:

        def rho(self, ops: Any, y: Any) -> Any: ...

    @property
    def is_empty(self) -> bool:
        """The density is 0 everywhere."""
        return self.density <= 0

    def max_density(self, ops: Any, y_lo: Any, y_hi: Any) -> Any:
        """Largest relative density on heights ``[y_lo, y_hi]``: at ``y_lo`` (non-increasing)."""
        return self.rho(ops, y_lo)


@dataclass(frozen=True)
class ProfileEntry:
    """A registered profile: its name, its parser ``(params, src) -> layers``,
    whether it needs ``bounds_min``/``bounds_max``, and optionally its own bounds
    parser ``(params, src) -> bounds object or None`` (e.g. Unreal's path-traced
    fog: a camera-centred cylinder, :mod:`fogref.media.ue_pathtracer`)."""

    name: str
    parse: Callable[[dict, str], tuple]
    needs_bounds: bool = False
    parse_bounds: Callable[[dict, str], Any] | None = None


#: XML profile name -> :class:`ProfileEntry` (filled by :func:`register_profile`).
PROFILES: dict[str, ProfileEntry] = {}


def register_profile(
    name: str,
    parse: Callable[[dict, str], tuple],
    needs_bounds: bool = False,
    parse_bounds: Callable[[dict, str], Any] | None = None,
) -> None:
    """Make ``profile="<name>"`` parse with ``parse(params, src) -> tuple of layers``.

    Parameters
    ----------
    name : str
        The ``heightfog`` XML ``profile`` value.
    parse : callable
        ``parse(params: dict, src: str)`` returning a tuple of 1 to 4
        :class:`HeightProfile` layers; raises ParameterError on a bad value.
    needs_bounds : bool
        The profile is only meaningful inside a box (``box``).
    parse_bounds : callable, optional
        ``parse_bounds(params, src)`` returning the profile's own bounds object
        (see :class:`fogref.media.medium.Box`) or None; such a profile takes no
        ``bounds_min``/``bounds_max``.

    Examples
    --------
    >>> from fogref.media import ExpLayer
    >>> from fogref.media.protocol import PROFILES, register_profile
    >>> register_profile("doc_example", lambda params, src: (ExpLayer(1.0, 0.0, 0.0),))
    >>> PROFILES["doc_example"].parse({}, "<doc>")
    (ExpLayer(density=1.0, falloff=0.0, height=0.0),)
    >>> del PROFILES["doc_example"]
    """
    PROFILES[name] = ProfileEntry(name, parse, needs_bounds, parse_bounds)


def profile_entry(name: str, src: str = "<params>") -> ProfileEntry:
    """The registered profile ``name``; ParameterError naming 'profile' if unknown.

    Examples
    --------
    >>> import fogref.media
    >>> profile_entry("box").needs_bounds
    True
    """
    return PROFILES[params.choice(name, "profile", PROFILES, src)]


def number(
    values: dict, key: str, default: float, src: str, lo: float = -math.inf, hi: float = math.inf
) -> float:
    """``values[key]`` (or ``default``) as a finite float in ``[lo, hi]`` (:func:`fogref.params.number`).

    Examples
    --------
    >>> number({"g": "0.5"}, "g", 0.0, "<doc>", -0.999, 0.999)
    0.5
    >>> number({}, "g", 0.0, "<doc>")
    0.0
    >>> number({"g": "x"}, "g", 0.0, "<doc>")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <doc>: parameter 'g': 'x' does not parse as a number
    """
    return params.number(values.get(key, default), key, source=src, lo=lo, hi=hi)


def rgb(
    v: Any, name: str = "colour", source: str = "<params>", lo: float = -math.inf, hi: float = math.inf
) -> tuple[float, float, float]:
    """An RGB triple (or a 3-vector) from 1 or 3 numbers, a sequence or a string
    (:func:`fogref.params.rgb`).

    Parameters
    ----------
    v : float, sequence of 1 or 3 floats, or str
        ``0.5``, ``[0.1, 0.2, 0.3]`` or ``"0.1, 0.2 0.3"`` (XML style).
    name, source : str
        Named in the ParameterError.
    lo, hi : float
        Every component must be finite and in ``[lo, hi]``.

    Returns
    -------
    tuple of 3 floats

    Examples
    --------
    >>> rgb(0.5)
    (0.5, 0.5, 0.5)
    >>> rgb("1, 2 3")
    (1.0, 2.0, 3.0)
    >>> rgb([1, 2], "albedo", "<doc>")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <doc>: parameter 'albedo': expected 1 or 3 numbers, got 2 ([1, 2])
    """
    return params.rgb(v, name, source=source, lo=lo, hi=hi)

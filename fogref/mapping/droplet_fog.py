"""Fog from what a meteorologist reports: visibility and the kind of fog -> heightfog parameters.

:func:`droplet_fog` turns a visibility (meteorological optical range, with its contrast
threshold: :mod:`fogref.media.visibility`) and a droplet size distribution
(:mod:`fogref.media.droplets`) into the ``heightfog`` medium's ``sigma_t``, ``albedo``,
``g`` and phase function (:mod:`fogref.media.mie`), at the fog's reference height:

* the droplets' number is set so that the green channel's (549.1 nm, the eye's)
  extinction is ``-ln(eps) / V``; the other channels follow from Mie theory (droplet
  extinction is grey within about 2 %), and so does the albedo (above 0.9999);
* the phase function is the droplets' Mie phase (``"mie"``: the channels' phases averaged
  with weights ``sigma_s``, one table for R, G and B: the colour of the fogbow and the
  glory is dropped), Jendersie and d'Eon's approximate Mie phase for droplets of diameter
  ``2 r_eff`` (``"approx-mie"``), or the Henyey-Greenstein phase of the Mie phase's mean
  cosine (``"hg"``, what fogref's truth had before droplets);
* ``g`` is the phase's mean cosine (the Mie phase's for ``"hg"``): it is what the engines'
  fog models keep (:mod:`fogref.mapping.engines` fits their lobes to the HG of ``g``).

What each engine's mapping keeps and drops (:data:`ENGINE_MAPPING`): every engine keeps
the extinction (grey engines only with ``grey=True``: the green channel's for all three)
and ``g``; none keeps the phase's shape (the diffraction peak, the fogbow, the glory).
With a visibility alone (no droplets) the fog is Koschmieder's grey fog, as Bevy's
``FogFalloff::from_visibility`` makes it, and keeps the given HG ``g``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from fogref.errors import ParameterError
from fogref.media.droplets import GammaDroplets, droplet_preset
from fogref.media.mie import droplet_optics
from fogref.media.ops import NP
from fogref.media.phase import TabulatedPhase, approx_mie_phase
from fogref.media.visibility import (
    KOSCHMIEDER_CONTRAST,
    extinction_from_visibility,
    visibility_from_extinction,
)

__all__ = ["ENGINE_MAPPING", "PHASES", "DropletFog", "droplet_fog"]

#: The phase functions a droplet fog can be written with
PHASES = ("mie", "approx-mie", "hg")

#: What the engines' mappings (fogref.mapping.engines) keep of a droplet fog, and what they drop
ENGINE_MAPPING = (
    "engines keep sigma_t (grey ones need it grey: --grey-extinction), the albedo and g (the phase's mean "
    "cosine, their lobes fitted to HG(g)); they drop the phase's shape: the diffraction peak, the fogbow and "
    "the glory"
)


@dataclass(frozen=True)
class DropletFog:
    """A droplet fog's ``heightfog`` parameters (see module).

    sigma_t: RGB extinction at the reference height [1/m].
    albedo:  RGB single-scattering albedo.
    g:       the phase's mean cosine (the HG's ``g`` when ``phase`` is None).
    phase:   the tabulated phase function, or None (Henyey-Greenstein with ``g``).
    visibility: the green channel's visibility [m] at the ``contrast`` threshold.
    number:  droplets per cm^3 (None without droplets).
    notes:   what was kept and dropped, for the scene's comments.
    """

    sigma_t: tuple
    albedo: tuple
    g: float
    phase: TabulatedPhase | None
    visibility: float
    contrast: float
    number: float | None = None
    notes: tuple = field(default=())

    def medium_params(self) -> dict[str, Any]:
        """The ``heightfog`` parameters (``sigma_t``, ``albedo``, ``g``, and ``phase`` as a
        ``fogtabphase``'s parameters when tabulated)."""
        out: dict[str, Any] = {"sigma_t": list(self.sigma_t), "albedo": list(self.albedo), "g": self.g}
        if self.phase is not None:
            out["phase"] = self.phase.as_params()
        return out


def droplet_fog(
    visibility: float | None = None,
    droplets: str | GammaDroplets | None = None,
    *,
    contrast: float = KOSCHMIEDER_CONTRAST,
    phase: str | None = None,
    grey: bool = False,
    g: float = 0.6,
    albedo: float = 0.9,
    src: str = "<droplet_fog>",
) -> DropletFog:
    """The fog of a visibility [m] (0 < V <= 1e6) and/or droplets (a preset name of
    :data:`fogref.media.droplets.DROPLET_PRESETS` or a :class:`GammaDroplets`); see module.

    Without ``visibility`` the droplets' own number sets it; without ``droplets`` the fog is
    grey with the HG ``g`` and ``albedo`` (``phase`` must then be ``"hg"``).  ``phase``: one of
    :data:`PHASES`; default ``"mie"`` with droplets, ``"hg"`` without.  ``grey``: the green channel's
    extinction for R, G and B.  Raises ParameterError naming the parameter.

    Examples
    --------
    >>> f = droplet_fog(1000.0)             # Koschmieder, 2 %: 3.912 / V
    >>> round(f.sigma_t[1], 6), f.phase is None, f.g, f.albedo
    (0.003912, True, 0.6, (0.9, 0.9, 0.9))
    >>> f = droplet_fog(300.0, "radiation")
    >>> round(f.sigma_t[1] * 300.0, 4), round(f.g, 3), f.phase.label
    (3.912, 0.832, 'mie radiation fog')
    >>> round(f.number, 1)   # droplets per cm^3 for V = 300 m
    302.4
    """
    phase = phase or ("hg" if droplets is None else "mie")
    if phase not in PHASES:
        raise ParameterError(src, "phase", f"'{phase}' is not one of {', '.join(PHASES)}")
    if visibility is None and droplets is None:
        raise ParameterError(src, "visibility", "give a visibility, droplets or both")
    if droplets is None:
        if phase != "hg":
            raise ParameterError(src, "phase", f"'{phase}' needs droplets (a Mie phase is the droplets')")
        assert visibility is not None
        s = extinction_from_visibility(visibility, contrast, src)
        note = (
            f"visibility {visibility:g} m at {contrast:g} contrast: grey extinction {s:.6g} /m (Koschmieder)"
        )
        return DropletFog(
            (s, s, s), (1.0, 1.0, 1.0), float(g), None, float(visibility), contrast, notes=(note,)
        )
    d = droplet_preset(droplets, src) if isinstance(droplets, str) else droplets
    name = droplets if isinstance(droplets, str) else d.label
    optics = droplet_optics(d)
    per_droplet = optics.extinction(1.0)  # 1/m per droplet per cm^3
    if visibility is None:
        number = d.number
        visibility = visibility_from_extinction(per_droplet[1] * number, contrast, src)
    else:
        number = extinction_from_visibility(visibility, contrast, src) / per_droplet[1]
    sigma = tuple(float(s * number) for s in per_droplet)
    if grey:
        sigma = (sigma[1],) * 3
    mie = optics.grey_phase(f"mie {name} fog")
    g_mie = mie.mean_cosine
    table: TabulatedPhase | None
    if phase == "mie":
        table = mie
    elif phase == "approx-mie":
        diameter = 2.0 * d.r_eff
        table = TabulatedPhase.from_function(
            lambda c: approx_mie_phase(NP, c, diameter), label=f"approx-mie {diameter:g} um"
        )
    else:
        table = None
    g_out = g_mie if table is None else table.mean_cosine
    notes = (
        f"{d.label}: r_eff {d.r_eff:g} um, v_eff {d.v_eff:.4g}; {number:.4g} droplets/cm^3 give visibility "
        f"{visibility:.4g} m at {contrast:g} contrast (green, 549.1 nm); Mie (miepython) per channel at "
        f"{', '.join(f'{w:g}' for w in optics.wavelengths)} nm",
        f"phase: {phase} ({'one table for R, G, B' if table is not None else 'HG of the Mie mean cosine'}); "
        f"g {g_out:.4f} is its mean cosine" + ("; extinction grey (green)" if grey else ""),
        ENGINE_MAPPING,
    )
    alb = tuple(float(a) for a in optics.albedo)
    return DropletFog(sigma, alb, g_out, table, float(visibility), contrast, number, notes)

"""Mitsuba medium plugin ``heightfog``: fogref's exact fog for stock integrators.

Stock ``volpath`` cannot call a Python medium's free-flight sampling (that method
is not virtual); it does delta tracking against ``get_majorant``.  This plugin
gives it a *tight per-ray majorant*: ``intersect_aabb`` clips the ray to the fog's
bounds and records the largest density on the clipped segment, which it asks the
height profiles for (``max_density`` over the segment's height range, see
:class:`fogref.media.protocol.HeightProfile`; a Local Fog Volume widens the segment to its chord
and adds its bound), and ``get_majorant`` returns it.  ``fogpath`` instead uses
:attr:`fog` (the physics object) for analytic free flight and closed-form transmittance.

XML parameters (SI units, y-up):

==============  =========  ==================================================  ========
name            type       meaning                                             default
==============  =========  ==================================================  ========
profile         string     ``exponential`` | ``homogeneous`` | ``box`` |      exponential
                           ``hdrp`` | ``powerlaw``
sigma_t         rgb/float  extinction at the reference height [1/m], 0..1e2   0.01
albedo          rgb/float  single-scattering albedo, 0..1                     0.9
g               float      Henyey–Greenstein asymmetry, -0.999..0.999         0
density         float      layer 1 relative density (>= 0)                    1
falloff         float      layer 1 falloff b [1/m], 0..1e3                    0.01
height          float      layer 1 reference height h [m]                     0
density2        float      layer 2 relative density; 0 = no second layer      0
falloff2        float      layer 2 falloff [1/m]                              0.01
height2         float      layer 2 reference height [m]                       0
base_height     float      ``hdrp``: top of the constant part [m]             0
start, end      float      ``powerlaw``: full and zero density heights [m]   0, 100
power           float      ``powerlaw``: exponent p >= 0                      1
bounds_min/max  point      the fog's box [m] (required for ``box``)           none
floor           float      lowest height the majorant considers [m] (stock     see text
                           integrators only): no ray may go below it in fog.
                           Default: bounds_min.y, else the lowest layer's
                           ``reference_height`` (scenes put it at ground level),
                           and the Local Fog Volume's lowest point.
lfv_centre      point      a Local Fog Volume's centre [m] (its parameters:   none
                           ``fogref.media.local_fog_volume``; its density
                           adds to the profile's, the bounds do not clip it)
lfv_radius      float      its radius [m], (0, 1e6]; required for a volume     none
lfv_density     float      its relative density at the centre, 0..1e6         1
lfv_falloff     float      its height falloff [1/m], 0..1e3                   0
lfv_height      float      its reference height [m]                           0
==============  =========  ==================================================  ========

A ``<phase>`` child replaces ``g``: an ``hg`` (its ``g``, which the physics then uses) or a
``fogtabphase`` (a tabulated phase function, e.g. a droplet fog's Mie phase:
``plugins/tab_phase.py``); other phase plugins are refused, since fogpath's closed forms
evaluate the phase function themselves.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from fogref.errors import ParameterError
from fogref.media import drjit_ops
from fogref.media.params import medium_from_params
from fogref.params import number as valid_number

from .tab_phase import TabulatedPhaseFunction


def _props_to_dict(props) -> dict:
    out = {}
    for key in props.keys():
        try:
            v = props[key]
        except Exception:
            continue
        if isinstance(v, (bool, int, float, str)):
            out[key] = v
        else:
            try:
                out[key] = [float(x) for x in v]
            except TypeError:
                pass
    return out


class _SegmentMajorant:
    """The majorant ``intersect_aabb`` found for the rays being traced, held where Dr.Jit's
    traversal does not enter (a plain object with slots).  ``dr.freeze`` traverses every
    registered Mitsuba object, this medium's attributes included; a majorant left on the medium
    by a finished render is a variable of that render's symbolic loop, which a later recording of
    any frozen function in the process (fogpath's passes) would take as an input and refuse
    (``jit_var_schedule(...): not permitted``)."""

    __slots__ = ("value",)

    def __init__(self):
        self.value = None


class HeightFogMedium(mi.Medium):
    """Exact fog medium (see module docstring); ``self.fog`` is the physics."""

    def __init__(self, props):
        params = _props_to_dict(props)
        src = f"heightfog '{props.id()}'" if props.id() else "heightfog"
        children = [props[k] for k in props.keys() if isinstance(props[k], mi.PhaseFunction)]
        has_phase = bool(children)
        for child in children:
            if isinstance(child, TabulatedPhaseFunction):
                params["phase"] = child.table
            elif "g" in mi.traverse(child).keys() and str(child).startswith("HGPhaseFunction"):
                params["g"] = float(mi.traverse(child)["g"][0])
            else:
                kind = str(child).split("[")[0]
                raise ParameterError(src, "phase", f"{kind}: heightfog takes hg or fogtabphase")
        self.fog = medium_from_params(params, src)
        if not has_phase:
            props["phase"] = mi.load_dict({"type": "hg", "g": self.fog.g}, parallel=False)
        super().__init__(props)
        default_floor = (
            self.fog.bounds.lo[1]
            if self.fog.bounds is not None
            else min(L.reference_height for L in self.fog.layers)
        )
        vol = self.fog.volume
        if vol is not None:  # not clipped by the bounds: its lowest point counts too
            default_floor = min(default_floor, vol.centre[1] - vol.radius)
        self.floor = valid_number(params.get("floor", default_floor), "floor", source=src, lo=-1e7, hi=1e7)
        self.m_is_homogeneous = False
        # Stock volpath's spectral mode gives every ray that escapes to infinity
        # weight 0 (its transmittance pdf uses t = inf), so stock comparisons need
        # grey extinction, which runs in its non-spectral mode.
        st = self.fog.sigma_t
        self.m_has_spectral_extinction = not (st[0] == st[1] == st[2])
        self._maj = _SegmentMajorant()

    # -- stock-integrator interface -----------------------------------------
    def intersect_aabb(self, ray):
        ops = drjit_ops()
        t0, t1 = self.fog.clip(ops, ray.o, ray.d)
        if self.fog.volume is not None:
            t0, t1 = self._with_volume(ops, ray, t0, t1)
        t1 = dr.minimum(t1, ray.maxt)
        active = t1 > t0
        # the segment's height range, floored; the profiles give their largest density on it
        far = dr.select(dr.isfinite(t1) & (t1 < 1e30), t1, 1e30)
        y0 = ray.o.y + t0 * ray.d.y
        y1 = ray.o.y + far * ray.d.y
        y_low = dr.maximum(dr.minimum(y0, y1), self.floor)
        y_high = dr.maximum(dr.maximum(y0, y1), y_low)
        if self.fog.bounds is not None and self.fog.volume is None:
            y_low = dr.maximum(y_low, self.fog.bounds.lo[1])
            y_high = dr.maximum(dr.minimum(y_high, self.fog.bounds.hi[1]), y_low)
        rho_max = self.fog.max_density(ops, y_low, y_high)
        # No additive floor: where the fog fades to nothing (rays rising out of
        # an unbounded layer) the majorant underflows to 0, the next tentative
        # collision lands at infinity and the ray escapes instead of taking
        # endless null steps.
        self._maj.value = mi.Float(rho_max) * 1.0001
        return active, dr.select(active, t0, dr.inf), dr.select(active, t1, dr.inf)

    def _with_volume(self, ops, ray, t0, t1):
        """The interval ``[t0, t1]`` of the bounds widened to the volume's chord (the bounds do
        not clip the volume): the smallest interval holding both."""
        c0, c1, _, _ = self.fog.volume.chord(ops, ray.o, ray.d)
        c0 = dr.maximum(c0, 0.0)
        meets, box = c1 > c0, mi.Float(t1) > t0
        t0 = dr.select(meets, dr.select(box, dr.minimum(t0, c0), c0), t0)
        t1 = dr.select(meets, dr.select(box, dr.maximum(t1, c1), c1), t1)
        return t0, t1

    def _majorant(self):
        maj = self._maj.value if self._maj.value is not None else mi.Float(1.0)
        return mi.UnpolarizedSpectrum(*(s * maj for s in self.fog.sigma_t))

    def get_majorant(self, mei, active=True):
        return self._majorant()

    def get_scattering_coefficients(self, mei, active=True):
        ops = drjit_ops()
        rho = self.fog.density(ops, mei.p)
        sigma_t = mi.UnpolarizedSpectrum(*(s * rho for s in self.fog.sigma_t))
        sigma_s = sigma_t * mi.UnpolarizedSpectrum(*self.fog.albedo)
        sigma_n = dr.maximum(self._majorant() - sigma_t, 0.0)
        return sigma_s, sigma_n, sigma_t

    def to_string(self):
        return f"HeightFogMedium[{self.fog!r}]"


def register() -> None:
    mi.register_medium("heightfog", lambda props: HeightFogMedium(props))


__all__ = ["HeightFogMedium", "register"]

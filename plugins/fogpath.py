"""``fogpath``: a path tracer for exact height fog, in Python with Dr.Jit loops.

The integrator, :class:`FogPathIntegrator` (parameters in its docstring), whose ``sample``
returns R,G,B and :data:`AOV_NAMES` per sample, rendered as per-pixel moments
(:meth:`FogPathIntegrator.render_moments`: what the render driver writes as means and
standard errors; ``mi.render`` in passes of at most :data:`fogref_plugins.passes.MAX_LANES`
lanes).  It has:

* **camera rays from the camera itself, to any distance**: the perspective
  sensor's near and far clip planes are ignored, so ``T`` and ``distance`` cover
  the first centimetre and surfaces beyond 10 km are seen;
* **analytic free flight** in the sensor's ``heightfog`` (each layer inverted in
  closed form, the nearest collision wins; RGB extinction by one-sample spectral
  MIS per segment, Veach & Guibas 1995 one-sample model); no majorant, no null
  collisions;
* **closed-form transmittance** on shadow rays times geometric visibility;
* **next-event estimation** with MIS (power heuristic) for the sun
  (``directional``), the sky (``constant``/``envmap``) and area lights;
  Henyey–Greenstein phase; any Mitsuba BSDF; ``max_depth`` and Russian roulette;
* **variance reduction on the camera ray** (its one stage, :meth:`FogPathIntegrator._camera_ray`):
  the sun's single scattering sampled from its exact integrand or a closed-form mixture
  (``sun_sampling``; :func:`fogref.media.single_scatter.sun_sampling_mode`; along every later
  segment too, ``sun_sampling_rays``), and forced
  splitting: both branches of the camera ray, the surface and a forced medium collision,
  in every sample (``forced_split``);
* **a constant sky at medium vertices** as the phase lobe's closed-form share above the horizon
  plus one phase sample's residual, where that wins (``sky_at_media``,
  :meth:`FogPathIntegrator._sky_residual_light`), the closed form taken as its mean along
  every segment after the camera ray (:meth:`FogPathIntegrator._sky_on_segment`);
* **the parts of the schema** per sample (:class:`Split`):
  ``L = attenuated_surface + single + multiple`` exactly.  How the parts, forced
  splitting and the sun's sampling fit together: ``docs/design.md``, "fogpath".

Scene values that are one Dr.Jit value (emitter radiance, transforms, ``g``, ...) are made
opaque before a render (:func:`make_scene_values_opaque`), so kernels are reused across
scenes that differ only in a value.

**Frozen passes** (``freeze``, default on): a pass is traced by Python the first time, recorded
with ``dr.freeze`` the :data:`RECORD_FROM_CALL`-th time and then replayed without running Python.
One frozen function per integrator (so per loaded scene); its inputs are the seed, the scene's
one-value parameters and a fingerprint of every Python value the trace reads
(:meth:`FogPathIntegrator._fingerprint`), so an edited value records anew instead of replaying
a stale one; a recording Dr.Jit refuses falls back to tracing with one warning
(``docs/design.md``, "Tracing was the fixed cost").

Not supported: sensors other than ``perspective``; media attached to shapes
(the fog fills all space outside surfaces); reconstruction filters other than
box (a warning says so); differentiation.

References: Novák et al., "Monte Carlo methods for volumetric light transport
simulation", Computer Graphics Forum 37(2), 2018 (free-flight sampling, spectral
MIS); Mitsuba 3, ``src/python/python/ad/integrators/prb.py`` (loop structure).
"""

from __future__ import annotations

import gc
import math

import drjit as dr
import mitsuba as mi
import numpy as np
from fogref_plugins.passes import max_lanes, pass_seed, pass_sizes
from mitsuba.python.ad.integrators.common import mis_weight  # the module set_variant loaded (not a 2nd copy)

from fogref import gbuffer, params
from fogref.errors import ParameterError
from fogref.media import NP, drjit_ops
from fogref.media import closed_form as cf
from fogref.media.single_scatter import (
    hg_upper_fraction_table,
    sample_sun_single_scatter,
    sample_sun_single_scatter_mixture,
    sun_sampling_mode,
)
from fogref.scene.vocabulary import MAX_DEPTH, Range

#: The integrator's AOVs (after R,G,B): the per-sample groups of the schema.
AOV_NAMES = gbuffer.sample_channel_names()

#: Dr.Jit's ``OptimizeLoops`` while fogpath traces a pass.  On, Dr.Jit traces every symbolic
#: loop body twice to drop loop-invariant state; off, once.  Off: about 20 ms less host time
#: per pass, pixels bitwise equal and execution time unchanged within noise
#: (``reports/benchmarks/host_time.md``).
OPTIMIZE_LOOPS = False

#: ``forced_split``'s default (see ``reports/benchmarks/variance_reduction_changes.md``)
FORCED_SPLIT_DEFAULT = True
#: ``sun_sampling_rays``'s default: every segment (see ``reports/benchmarks/sun_segments.md``)
SUN_SAMPLING_RAYS_DEFAULT = -1
#: ``sun_sampling_rays``'s values: -1 (every segment) or a count of segments
SUN_SAMPLING_RAYS = Range(None, "depth", -1, 2**31 - 1)
#: ``sky_at_surfaces``'s default (see ``reports/benchmarks/summary.md``)
SKY_AT_SURFACES_DEFAULT = "bsdf"
#: ``sky_at_media``'s default (see ``reports/benchmarks/sky_residual.md``)
SKY_AT_MEDIA_DEFAULT = "auto"
#: With ``sky_at_media = "auto"``, the residual is used where the camera's transmittance straight
#: up (mean over RGB) is at least this: below it the fog dims the sky while the control variate
#: ``B`` is not, and next-event estimation wins at equal time (``reports/benchmarks/sky_residual.md``:
#: the open valley with its fog 16x denser, 0.34 up, gained 1.5x, with 32x, 0.12 up, lost 0.59x).
SKY_RESIDUAL_MIN_UP_TRANSMITTANCE = 0.25
#: ... and the surface straight below the camera has a diffuse reflectance (mean over RGB) of at
#: most this: a white world lights the fog from below as brightly as the sky, and there next-event
#: estimation wins (``reports/benchmarks/sky_residual.md``: 0.9 under a sky alone lost).
SKY_RESIDUAL_MAX_REFLECTANCE = 0.7
#: Stratified sun samples per camera ray (each one shadow ray): 4 against 2 gains 1.38x at equal
#: time on both valleys, where the terrain's shadows along the camera ray are most of what is left,
#: and costs 4-8 % where they are not (``reports/benchmarks/sun_samples.md``).
SUN_SAMPLES = 4


#: The call of a fingerprint (:meth:`FogPathIntegrator._fingerprint`) from which an integrator's
#: passes run under ``dr.freeze``: earlier calls are traced.  Recording a pass costs more host
#: time than tracing it (28 ms more at 32x18, paired, ``reports/benchmarks/frozen_render.md``), so a
#: one-pass render is traced as before, and the second pass of its kind (or the second render
#: of a kept scene, :func:`fogref.render.load.loaded_scene`) records.
RECORD_FROM_CALL = 2
#: Recordings kept per integrator (least recently used dropped), and fingerprints counted.
KEEP_RECORDINGS, KEEP_FINGERPRINTS = 8, 64


def _plain(v):
    """``v`` (numbers, strings, containers, plain Python objects such as the fog's dataclasses)
    as nested tuples that compare equal exactly when the values are bitwise equal: floats as
    ``float.hex`` (``-0.0`` differs from ``0.0``, which ``==`` does not tell apart), objects
    by type and attributes, anything else by ``repr``.

    >>> _plain({"g": -0.0, "layers": [1, (0.5, "a")]})
    (('g', '-0x0.0p+0'), ('layers', (1, ('0x1.0000000000000p-1', 'a'))))
    """
    if v is None or isinstance(v, (bool, int, str)):
        return v
    if isinstance(v, float):
        return float.hex(v)
    if isinstance(v, (tuple, list)):
        return tuple(_plain(x) for x in v)
    if isinstance(v, dict):
        return tuple(sorted(((str(k), _plain(x)) for k, x in v.items()), key=lambda kv: kv[0]))
    if hasattr(v, "tobytes") and hasattr(v, "dtype"):  # a numpy array
        return (str(v.dtype), tuple(v.shape), v.tobytes())
    if hasattr(v, "__dict__") and not isinstance(v, type):
        return (type(v).__qualname__, _plain(vars(v)))
    return repr(v)


def _frozen_pass(scene, sensor, seed, spp, pixel_exact, squares, values, tables, fingerprint):
    """A pass as ``dr.freeze`` records and replays it: :meth:`FogPathIntegrator._pass` of the
    scene's integrator, with ``tables`` (the fog's interpolation tables, as received: inputs of
    the recording) as the ones it reads.  ``values`` (the scene's one-value parameters) and
    ``fingerprint`` are inputs only: the first makes their current values the replay's, the
    second makes a change of any Python value the trace reads a new recording."""
    return scene.integrator()._pass_reading(tables, scene, sensor, seed, spp, pixel_exact, squares)


class _Held:
    """The scene whose values a ``render_moments`` call read, and those values (a dict), where
    Dr.Jit's traversal of the integrator's attributes does not enter (:meth:`FogPathIntegrator._read_once`).
    Compared by identity."""

    __slots__ = ("obj", "values")

    def __init__(self, obj, values):
        self.obj, self.values = obj, values

    def __eq__(self, other):
        return self is other

    __hash__ = object.__hash__


class _FrozenPasses:
    """One integrator's frozen passes: its ``dr.freeze`` function (made on first use, so that
    recordings die with the integrator and its scene), how often each fingerprint was seen
    (:data:`RECORD_FROM_CALL`) and, once Dr.Jit refused to record, its reason (then every pass
    is traced).  Compared by identity: Dr.Jit sees it, unchanged, among the integrator's
    attributes while its contents change."""

    __slots__ = ("frozen", "calls", "refused")

    def __init__(self):
        self.frozen, self.calls, self.refused = None, {}, None

    def __eq__(self, other):
        return self is other

    __hash__ = object.__hash__

    def run(self, fp, scene, sensor, seed, spp, pixel_exact, squares):
        """``fp._pass(scene, sensor, seed, spp, pixel_exact, squares)``: traced on the first call
        of its fingerprint, recorded with ``dr.freeze`` on the :data:`RECORD_FROM_CALL`-th,
        replayed after; always traced when the scene is not ``fp``'s or after a refusal (one
        warning)."""
        args = (scene, sensor, seed, spp, pixel_exact, squares)
        if self.refused is not None or scene.integrator() is not fp:
            return fp._pass(*args)
        key = fp._fingerprint(scene, sensor, spp, pixel_exact, squares)
        if key not in self.calls and len(self.calls) >= KEEP_FINGERPRINTS:
            self.calls.clear()
        self.calls[key] = n = self.calls.get(key, 0) + 1
        if n < RECORD_FROM_CALL:
            return fp._pass(*args)
        if self.frozen is None:
            self.frozen = dr.freeze(_frozen_pass, limit=KEEP_RECORDINGS, warn_after=1 << 30)
        values = {k: v for k, v in mi.traverse(scene).items() if dr.is_jit_v(v) and dr.width(v) == 1}
        collecting = gc.isenabled()
        gc.disable()  # a collection freeing a failed recording's arrays during a recording aborts Dr.Jit
        try:
            return self.frozen(*args, values, fp._fog_tables(scene), key)
        except RuntimeError as e:
            cause = e
            while cause.__cause__ is not None:
                cause = cause.__cause__
            if not isinstance(cause, RuntimeError) or "KeyboardInterrupt" in str(cause):
                raise cause from None  # the pass's own error (or an interruption), not a refusal
            self.refused = (str(cause).strip().splitlines() or [type(cause).__name__])[0]
            x: BaseException | None = e
            while x is not None:  # the failed recording's frames (and arrays) go now, not in a collection
                x.__traceback__, x = None, x.__cause__
        finally:
            if collecting:
                gc.enable()
        mi.Log(
            mi.LogLevel.Warn,
            f"fogpath: dr.freeze refused to record a pass ({self.refused}); this integrator "
            "traces its passes from now on",
        )
        return fp._pass(*args)


class _Opaque:
    """Hides a Python object (e.g. a dataclass) from Dr.Jit's loop-state traversal."""

    __slots__ = ("_obj",)

    def __init__(self, obj):
        object.__setattr__(self, "_obj", obj)

    def __getattr__(self, name):
        return getattr(self._obj, name)


class Split:
    """Where a contribution goes: ``surface`` (camera ray reached the surface or sky
    unscattered; the camera segment's weight is applied at the end), ``single``
    (direct light at the first medium vertex) or ``multiple``."""

    DRJIT_STRUCT = {"surface": mi.Spectrum, "single": mi.Spectrum, "multiple": mi.Spectrum}

    def __init__(self, surface=None, single=None, multiple=None):
        self.surface = mi.Spectrum(0.0) if surface is None else surface
        self.single = mi.Spectrum(0.0) if single is None else single
        self.multiple = mi.Spectrum(0.0) if multiple is None else multiple

    def add(self, c, medium_first, direct):
        return Split(
            self.surface + dr.select(medium_first, 0.0, c),
            self.single + dr.select(medium_first & direct, c, 0.0),
            self.multiple + dr.select(medium_first & ~direct, c, 0.0),
        )


class Trace:
    """What one ``sample`` call traces with, fixed for the call (Python values, no loop state):
    the scene, its fog (None: vacuum), the Dr.Jit ops, the fog's phase function (None: the fog
    does not scatter) and the phase and BSDF contexts, whether the scene has non-delta emitters
    (``has_smooth``) and any emitter (``has_lights``), and whether the sun's scattering along the
    camera ray is sampled along it (``sun_along``; then medium vertices on it skip sun NEE), and
    with ``sky_at_media``'s residual its :class:`SkyResidual` (``sky_residual``, else None)."""

    def __init__(self, scene, fog, phase, sampler, has_delta, has_smooth, sky_residual=None):
        self.scene, self.fog, self.ops, self.phase = scene, fog, drjit_ops(), phase
        self.phase_ctx, self.bsdf_ctx = mi.PhaseFunctionContext(sampler), mi.BSDFContext()
        self.has_delta, self.has_smooth, self.sun_along = has_delta, has_smooth, False
        self.has_lights, self.sky_residual = has_delta or has_smooth, sky_residual


class SkyResidual:
    """What ``sky_at_media``'s residual reads in Python (trace-time floats): the fog's ``g``,
    whose phase lobe's share above the horizon is tabulated
    (:func:`~fogref.media.single_scatter.hg_upper_fraction_table`, :attr:`share`), and the diffuse
    reflectance ``rho`` and sunlight ``sun`` (RGB radiance) of the surface below the camera
    (:meth:`FogPathIntegrator._surface_below`), whose radiance under the sky ``L`` is the control
    variate's light from below the horizon, ``B = rho (L + sun)``."""

    def __init__(self, g, rho, sun):
        self.g, self.rho, self.sun = float(g), tuple(rho), tuple(sun)

    @property
    def share(self) -> tuple:
        """The table of the lobe's share above the horizon on [-1, 1] (kept per ``g``)."""
        return hg_upper_fraction_table(self.g)


class Path:
    """The path loop's state where the loop takes it up: the parts so far (``split``), the
    throughput ``β`` and the camera segment's weight of unscattered paths ``β_cam``, the depth,
    whether the camera ray scattered first (``medium_first``), the ray and its hit ``si``, the
    vertex the ray leaves with its sampling pdf and deltaness (for MIS), and the live lanes."""

    def __init__(self, ray, si, active, depth=0):
        self.split, self.β, self.β_cam = Split(), mi.Spectrum(1.0), mi.Spectrum(1.0)
        self.depth, self.medium_first = mi.UInt32(depth), mi.Bool(False)
        self.ray, self.si, self.active = ray, si, active
        self.prev_it, self.prev_pdf = dr.zeros(mi.Interaction3f), mi.Float(1.0)
        self.prev_delta = mi.Bool(True)


class CameraRay:
    """The camera ray's stage: its G-buffer (None without ``aovs``), the sun's single scattering
    sampled along it (None where next-event estimation covers it), with forced splitting the
    sample of ``surface`` (``cover``, a :class:`Cover`; None without), and the :class:`Path` the
    loop continues."""

    def __init__(self, gbuf, sun_ss, cover, path):
        self.gbuf, self.sun_ss, self.cover, self.path = gbuf, sun_ss, cover, path


class Cover:
    """Forced splitting's sample of ``surface``: the lanes that continued the surface branch
    (``chosen``; for the sky: drew it with the same ``q``), the surface branch's depth-0 light
    (``direct``) and the probability ``q`` of continuing it."""

    def __init__(self, chosen, direct, q):
        self.chosen, self.direct, self.q = chosen, direct, q


def spectrum(values):
    """``mi.Spectrum`` of three channel values, or of one value for every channel."""
    return mi.Spectrum(*values) if len(values) == 3 else mi.Spectrum(values[0])


def make_scene_values_opaque(scene) -> int:
    """Make the scene's one-value Dr.Jit parameters (emitter radiance and irradiance,
    transforms, BSDF colours, the phase function's ``g``, ...) opaque, in place.

    Mitsuba traces such values into kernels as literals, so a scene that differs
    only in the sun's colour or the fog's ``g`` would compile new kernels;
    opaque, the kernels are reused (a sweep's configurations share them).  Values
    are unchanged.  Returns how many parameters were changed.
    """
    params = mi.traverse(scene)
    changed = 0
    for key in params.keys():
        value = params[key]
        if not (dr.is_jit_v(value) and dr.width(value) == 1):
            continue
        before = dr.detail.collect_indices(value)
        dr.make_opaque(value)
        if dr.detail.collect_indices(value) != before:  # was a literal: tell the object
            params[key] = value
            changed += 1
    if changed:
        params.update()
    return changed


class FogPathIntegrator(mi.SamplingIntegrator):
    """Path tracer with analytic free flight in fogref's exact fog (see module).

    .. pluginparameters::

     * - max_depth
       - int
       - Longest path (Mitsuba's convention: 1 = emitters seen directly only,
         2 = single scattering; -1 = no limit). Default: 64.
     * - rr_depth
       - int
       - Depth where Russian roulette starts. Default: 5.
     * - hide_emitters
       - bool
       - Camera rays that escape see black instead of the sky and the sun disk. Unlike stock
         ``path``/``volpath``, an area light seen directly stays visible. Default: false.
     * - aovs
       - bool
       - Write the per-sample parts and G-buffer of :mod:`fogref.gbuffer` after
         R,G,B (needed by ``fogref render``). Default: true.
     * - pixel_exact
       - bool
       - Every sample goes through the pixel's centre: the G-buffer and ``T`` are exact
         (no silhouette mixing); off, samples are uniform over the pixel (a box filter),
         for pictures. Default: false (``fogref render`` sets it for truths).
     * - sun_sampling
       - bool
       - Sample the sun's single scattering along camera rays from its exact integrand
         (zero variance without shadows; the first medium vertex then skips sun NEE), for
         unbounded exponential layers and a sun above the horizon (not with a Local Fog
         Volume: next-event estimation then samples the sun). Default: true.
     * - sun_sampling_rays
       - int
       - Path segments, from the camera ray on, along which ``sun_sampling`` samples the sun's
         scattering from its integrand: 1 (the camera ray), ``n`` (also the ``n - 1`` segments
         after it; on each, one sample and shadow ray, and the medium vertices on it skip sun
         NEE) or -1 (every segment).  Default: ``SUN_SAMPLING_RAYS_DEFAULT``.
     * - sun_angular_diameter
       - float
       - The sun's angular diameter [deg], in [0, 10]: 0 is a delta (Mitsuba's ``directional``);
         above 0 the sun is a uniform disk of the same irradiance, sampled in next-event
         estimation (uniform cone, pdf ``1 / (2 pi (1 - cos theta_max))``, radiance
         ``E / Omega``; along camera rays, ``sun_sampling``'s exact sampler aims at a point of
         the disk drawn per sample when the whole disk is above the horizon, else next-event
         estimation covers it).  A camera ray that reaches the sky through the disk sees its
         radiance ``E / Omega``, attenuated by the fog as the sky is. Default: 0.
     * - sky_at_surfaces
       - string
       - How a ``constant`` sky lights surfaces: ``mis`` (next-event estimation and the
         BSDF sample, power heuristic, as Mitsuba's ``path``) or ``bsdf`` (the BSDF sample
         alone, weight 1; next-event estimation keeps the sun and other emitters).  With
         ``bsdf`` a Lambertian surface that sees the whole sky gets it with zero variance
         (a cosine-weighted sample of a constant radiance).  Other skies always use
         ``mis``.  Default: ``SKY_AT_SURFACES_DEFAULT``.
     * - sky_at_media
       - string
       - How a ``constant`` sky lights medium vertices: ``mis`` (next-event estimation among all
         emitters and the phase sample, power heuristic) or ``residual``: the sky's light is
         ``L H(d_y) + B (1 - H(d_y)) + w (L V T - c(w))`` (:meth:`_sky_residual_light`), ``H``
         the share of the phase lobe around the ray's direction ``d`` above the horizon (closed
         form, within 7e-7), ``w`` the continuation's own phase sample, ``V T`` its visibility and
         transmittance to the sky, ``c(w)`` the sky's radiance ``L`` above the horizon and ``B``
         (the surface below the camera, lit) below it; next-event estimation keeps the delta
         lights.  On the path's segments after the camera ray the closed form ``L H + B (1 - H)``
         is added as its mean along the segment, ``albedo (1 - T(D)) (L H + B (1 - H))``, a
         surface the segment ends on subtracts ``B`` (the segment adds ``T(D) B``), and a
         vertex's residual is taken on the segment the path continues on, whose hit and
         transmittance it uses (:meth:`_sky_on_segment`): no ray of its own, and no variance from
         whether a later segment scatters.  ``residual`` needs a
         Henyey-Greenstein fog with ``|g| <= 0.94``, a constant sky and only delta lights
         besides; asked for elsewhere, the error says what is missing.
         ``auto`` takes it where it applies, the camera's transmittance straight up is at least
         ``SKY_RESIDUAL_MIN_UP_TRANSMITTANCE`` and the surface below the camera reflects at most
         ``SKY_RESIDUAL_MAX_REFLECTANCE``, else ``mis`` (:meth:`sky_at_media_for` says which).
         Default: ``SKY_AT_MEDIA_DEFAULT``.
     * - forced_split
       - bool
       - Forced splitting on the camera ray: every sample traces both branches at
         depth 0, the surface (or sky) weighted by the closed-form transmittance
         ``T`` and a forced medium collision on ``[0, D]`` with its light sample;
         the path then continues one branch, chosen in proportion to the branches'
         depth-0 throughputs (see :meth:`_camera_split`).  Used when the fog
         scatters, has no Local Fog Volume and ``max_depth >= 2``.  Default: ``FORCED_SPLIT_DEFAULT``.
     * - freeze
       - bool
       - Run passes under ``dr.freeze`` (see module): the same pixels, bitwise, with ~2 ms of
         host time per replayed pass instead of tracing it; false traces every pass.  Also
         settable as an attribute.  Default: true.
    """

    def __init__(self, props):
        super().__init__(props)
        # checked by fogref's one validator (its ParameterError is a ValueError)
        md = MAX_DEPTH.check(props.get("max_depth", 64), "max_depth", "fogpath")
        self.max_depth = 2**31 - 1 if md < 0 else md
        self.rr_depth = params.integer(
            props.get("rr_depth", 5), "rr_depth", source="fogpath", lo=1, hi=2**31 - 1
        )
        self.hide_emitters = bool(props.get("hide_emitters", False))
        self.sun_sampling = bool(props.get("sun_sampling", True))
        rays = SUN_SAMPLING_RAYS.check(
            props.get("sun_sampling_rays", SUN_SAMPLING_RAYS_DEFAULT), "sun_sampling_rays", "fogpath"
        )
        self.sun_sampling_rays = 2**31 - 1 if rays < 0 else rays
        self.forced_split = bool(props.get("forced_split", FORCED_SPLIT_DEFAULT))
        self.sky_at_surfaces = str(props.get("sky_at_surfaces", SKY_AT_SURFACES_DEFAULT))
        params.choice(self.sky_at_surfaces, "sky_at_surfaces", ("mis", "bsdf"), "fogpath")
        self.sky_at_media = str(props.get("sky_at_media", SKY_AT_MEDIA_DEFAULT))
        params.choice(self.sky_at_media, "sky_at_media", ("auto", "mis", "residual"), "fogpath")
        diameter = params.number(
            props.get("sun_angular_diameter", 0.0), "sun_angular_diameter", source="fogpath", lo=0.0, hi=10.0
        )
        #: 1 - cos of the sun disk's angular radius (float64), None for the delta sun
        self.sun_one_minus_cos = 2.0 * math.sin(math.radians(diameter) / 4.0) ** 2 if diameter > 0 else None
        self.aovs = bool(props.get("aovs", True))
        self.pixel_exact = bool(props.get("pixel_exact", False))
        self.freeze = bool(props.get("freeze", True))
        #: with ``sky_at_media``'s residual, the sky's closed form on the path's segments after the
        #: camera ray is their mean and a vertex's residual is sampled on the next segment
        #: (:meth:`_sky_on_segment`), not both at the vertex; false only in
        #: ``benchmarks/_fogpath_knobs.py``, which measures it against the vertices' way
        self.sky_along_segments = True
        #: with :attr:`sky_along_segments`, a surface a segment after the camera ray ends on subtracts
        #: ``B`` (the surface below the camera, lit) and the segment adds its mean (:meth:`_sky_on_segment`)
        self.surface_control = True
        self._frozen = _FrozenPasses()

    @property
    def n_recordings(self) -> int:
        """How many times Dr.Jit recorded this integrator's pass (``dr.freeze``'s
        ``n_recordings``; 0 before its first recording and with ``freeze`` off)."""
        f = self._frozen.frozen
        return 0 if f is None else int(f.n_recordings)

    @property
    def freeze_refused(self) -> str | None:
        """Dr.Jit's reason for refusing to record a pass (then every pass is traced), or None."""
        return self._frozen.refused

    def aov_names(self):
        return list(AOV_NAMES) if self.aovs else []

    # ------------------------------------------------------------ scene facts
    @staticmethod
    def _scene_fog(scene):
        """The physics object of the sensor's heightfog medium (None: vacuum)."""
        sensors = scene.sensors()
        med = sensors[0].get_medium() if sensors else None
        fog = getattr(med, "fog", None)
        if fog is None or fog.is_vacuum:
            return None
        return _Opaque(fog)

    @staticmethod
    def _scene_lights(scene):
        delta = [mi.has_flag(e.flags(), mi.EmitterFlags.Delta) for e in scene.emitters()]
        return any(delta), not all(delta)

    def _read_once(self, scene, name, read):
        """``read()``, read once per :meth:`render_moments` call and scene: the scene values
        fogpath reads while tracing (``str`` and ``float`` of evaluated variables, each a
        wait on the device) are read once per render instead of at every call site.
        Outside ``render_moments`` (``sample`` called directly) every call reads."""
        memo = getattr(self, "_memo", None)
        if memo is None or memo.obj is not scene:
            return read()
        if name not in memo.values:
            memo.values[name] = read()
        return memo.values[name]

    def _constant_sky(self, scene):
        """The scene's ``constant`` sky emitter when it is the only non-delta infinite
        emitter, else None (trace-time)."""
        return self._read_once(scene, "sky", lambda: self._read_constant_sky(scene))

    @staticmethod
    def _read_constant_sky(scene):
        smooth_inf = [
            e
            for e in scene.emitters()
            if mi.has_flag(e.flags(), mi.EmitterFlags.Infinite)
            and not mi.has_flag(e.flags(), mi.EmitterFlags.Delta)
        ]
        if len(smooth_inf) == 1 and str(smooth_inf[0]).startswith("ConstantBackgroundEmitter"):
            return smooth_inf[0]
        return None

    def _sky_selection(self, scene):
        """(the constant sky's probability of being chosen by ``scene.sample_emitter``, the
        summed probability of the emitters before it): trace-time floats."""
        return self._read_once(scene, "sky_selection", lambda: self._read_sky_selection(scene))

    def _read_sky_selection(self, scene):
        sky = self._constant_sky(scene)
        probs = [float(scene.pdf_emitter(i)[0]) for i in range(len(scene.emitters()))]
        j = next(i for i, e in enumerate(scene.emitters()) if e is sky)
        return probs[j], sum(probs[:j])

    def _scene_sun(self, scene):
        """(direction toward the sun, RGB irradiance) of the only delta directional
        emitter, or None (trace-time, Python floats)."""
        return self._read_once(scene, "sun", lambda: self._read_scene_sun(scene))

    @staticmethod
    def _read_scene_sun(scene):
        delta = [e for e in scene.emitters() if mi.has_flag(e.flags(), mi.EmitterFlags.Delta)]
        if len(delta) != 1:
            return None
        p = mi.traverse(delta[0])
        if "irradiance.value" not in p or "to_world" not in p:
            return None
        m = p["to_world"].matrix
        w = [-float(m[i][2][0]) for i in range(3)]
        n = sum(x * x for x in w) ** 0.5
        E = p["irradiance.value"]
        E = [float(E[i][0]) for i in range(3)] if len(E) == 3 else [float(E[0][0])] * 3
        return [x / n for x in w], E

    def _sky_residual(self, scene):
        """The :class:`SkyResidual` when medium vertices take the sky's closed form plus
        residual (``sky_at_media``), else None, also for a fog that does not scatter (trace-time,
        read once).  ``residual`` where it does not apply: a ParameterError naming
        ``sky_at_media`` and what is missing.  ``auto`` takes it where it applies, the camera's
        transmittance straight up is at least :data:`SKY_RESIDUAL_MIN_UP_TRANSMITTANCE` and
        the surface below the camera reflects at most :data:`SKY_RESIDUAL_MAX_REFLECTANCE`."""
        return self._read_once(scene, "sky_residual", lambda: self._read_sky_residual(scene))

    def sky_at_media_for(self, scene) -> str:
        """How medium vertices of ``scene`` take its constant sky: ``"residual"`` or ``"mis"``
        (``sky_at_media`` resolved for the scene; ``"mis"`` also where the fog does not scatter).
        ``residual`` asked for where it does not apply: the ParameterError a render raises."""
        return "mis" if self._sky_residual(scene) is None else "residual"

    def _read_sky_residual(self, scene):
        fog = self._scene_fog(scene)
        if self.sky_at_media == "mis" or fog is None or not fog.scatters:
            return None
        fog, sky = fog._obj, self._constant_sky(scene)
        share = None if fog.phase is not None else hg_upper_fraction_table(fog.g)
        missing = (
            "a constant sky"
            if sky is None
            else "only delta lights besides the sky"
            if sum(not mi.has_flag(e.flags(), mi.EmitterFlags.Delta) for e in scene.emitters()) > 1
            else f"a Henyey-Greenstein phase (the fog's is '{fog.phase.label}')"
            if fog.phase is not None
            else f"|g| <= 0.94 (g = {fog.g:g}: the lobe's share above the horizon needs a higher degree)"
            if share is None
            else None
        )
        if missing is not None:
            if self.sky_at_media == "residual":
                raise ParameterError("fogpath", "sky_at_media", f"'residual' needs {missing}")
            return None
        camera = scene.sensors()[0].world_transform().translation()  # opaque: no kernel per position
        rho, sun_below = self._surface_below(scene, fog, camera)
        o = [float(camera[i][0]) for i in range(3)]
        up = float(np.mean(fog.transmittance(NP, o, (0.0, 1.0, 0.0), math.inf)))
        nee_wins = up < SKY_RESIDUAL_MIN_UP_TRANSMITTANCE or sum(rho) / 3.0 > SKY_RESIDUAL_MAX_REFLECTANCE
        if self.sky_at_media == "auto" and nee_wins:
            return None
        return SkyResidual(fog.g, rho, sun_below)

    def _surface_below(self, scene, fog, camera):
        """(``rho``, ``S``) of the surface straight below the camera: its diffuse reflectance and
        the radiance the sun gives it, unshadowed, ``E max(w_y, 0) T_sun / pi`` (``T_sun`` the
        fog's transmittance from it toward the sun); RGB, trace-time Python floats, finite, 0
        when nothing is below the camera."""
        si = scene.ray_intersect(mi.Ray3f(camera, mi.Vector3f(0.0, -1.0, 0.0)))
        r = si.bsdf().eval_diffuse_reflectance(si)  # 0 where nothing is hit
        read = [dr.select(si.is_valid(), 1.0, 0.0), r[0], r[1], r[2], si.p.x, si.p.y, si.p.z]
        dr.eval(read)  # one kernel, then plain reads
        hit, *rgb, px, py, pz = (float(v[0]) for v in read)
        if hit == 0.0:
            return (0.0,) * 3, (0.0,) * 3
        rho = tuple(v if math.isfinite(v) else 0.0 for v in rgb)
        sun = self._scene_sun(scene)
        if sun is None or sun[0][1] <= 0:
            return rho, (0.0,) * 3
        T = fog.transmittance(NP, [px, py, pz], tuple(sun[0]), math.inf)
        return rho, tuple(e * sun[0][1] * float(t) / math.pi for e, t in zip(sun[1], T))

    def _sky_by_bsdf(self, scene):
        """Does the BSDF sample alone carry a constant sky at surfaces (trace-time)?"""
        return self.sky_at_surfaces == "bsdf" and self._constant_sky(scene) is not None

    # --------------------------------------------------------------- pieces
    def _transmittance(self, fog, ops, o, d, t):
        tau = fog.optical_depth(ops, o, d, t)
        return spectrum([dr.exp(-s * tau) for s in ops.params(fog.sigma_t)])

    def _draw_channel(self, sampler, active=True):
        return mi.UInt32(dr.minimum(mi.UInt32(sampler.next_1d(active) * 3.0), 2))

    @staticmethod
    def _medium_interaction(ray, p, t):
        mei = dr.zeros(mi.MediumInteraction3f)
        mei.p, mei.t, mei.wi = p, t, -ray.d
        mei.sh_frame = mi.Frame3f(mei.wi)
        mei.time, mei.wavelengths = ray.time, ray.wavelengths
        return mei

    @staticmethod
    def _vertex(ray, si, surf, p_med):
        """The interaction a sampled direction leaves from (for MIS on emitters it hits):
        a surface's, or at a medium vertex one with normal 0."""
        it = dr.zeros(mi.Interaction3f)
        it.p = dr.select(surf, si.p, p_med)
        it.n = dr.select(surf, si.n, 0.0)
        it.t = dr.select(surf, si.t, 0.0)
        it.time, it.wavelengths = ray.time, ray.wavelengths
        return it

    def _free_flight(self, tr, sampler, ray, t_surf, active):
        """Sample the next medium event before ``t_surf``.

        Returns (is_medium, t, weight): weight multiplies the throughput, i.e.
        sigma_s T / pdf at a medium vertex and T / P(pass) otherwise.  RGB
        extinction: one-sample spectral MIS *per segment*: a channel is drawn
        uniformly for this segment alone and the weight divides by the mean pdf
        over channels.  (Keeping one channel for a whole path while dividing each
        segment by its mean pdf is biased: 0.35 % too bright in the RGB furnace
        test, ``tests/test_render_bias.py``.)
        """
        fog, ops = tr.fog, tr.ops
        if fog is None:
            return mi.Bool(False), dr.minimum(t_surf, ops.largest), mi.Spectrum(1.0)
        if not fog.scatters:  # absorption only: deterministic, exact
            t_end = dr.minimum(t_surf, ops.largest)
            return mi.Bool(False), t_end, self._transmittance(fog, ops, ray.o, ray.d, t_end)
        sig_rgb = ops.params(fog.sigma_t)
        sig = sig_rgb[0]
        if fog.sigma_t[1] != fog.sigma_t[0] or fog.sigma_t[2] != fog.sigma_t[0]:
            channel = self._draw_channel(sampler, active)
            sig = dr.select(channel == 1, sig_rgb[1], dr.select(channel == 2, sig_rgb[2], sig))
        variates = [-dr.log(1.0 - sampler.next_1d(active)) for _ in range(fog.free_flight_variates)]
        t_med = fog.sample_distance(ops, ray.o, ray.d, variates, sig)
        is_medium = active & (t_med < t_surf) & (t_med < ops.largest)
        t_end = dr.select(is_medium, t_med, dr.minimum(t_surf, ops.largest))
        Tr = self._transmittance(fog, ops, ray.o, ray.d, t_end)
        rho = fog.density(ops, ray.o + ray.d * dr.select(is_medium, t_med, 0.0))
        sigma_t = spectrum([s * rho for s in sig_rgb])
        st = sigma_t * Tr
        pdf = dr.select(is_medium, (st[0] + st[1] + st[2]) / 3.0, (Tr[0] + Tr[1] + Tr[2]) / 3.0)
        num = dr.select(is_medium, sigma_t * spectrum(ops.params(fog.albedo)) * Tr, Tr)
        return is_medium, t_end, dr.select(pdf > 0, num / pdf, 0.0)

    def _direct(self, tr, sampler, it, scatter, active, but_sky=None):
        """Next-event estimation at ``it`` (a medium interaction when ``scatter`` is a
        phase function, else a surface interaction and ``scatter`` its BSDF): emitter
        sample times the closed-form fog transmittance and visibility, times the phase
        function or BSDF, MIS-weighted against it for non-delta emitters.
        Returns (contribution without the path throughput, is the sample delta).  With ``but_sky``
        (a trace-time bool) the constant sky is left out: the other emitters are sampled
        (:meth:`_sample_emitter_but_sky`) and a sample of the sky contributes 0.  Its default:
        at a surface with ``sky_at_surfaces = "bsdf"``, where the BSDF sample carries the sky
        alone (:meth:`_sky_by_bsdf`)."""
        scene, fog, ops = tr.scene, tr.fog, tr.ops
        in_medium = isinstance(scatter, mi.PhaseFunction)
        ctx = tr.phase_ctx if in_medium else tr.bsdf_ctx
        sky_by_bsdf = (not in_medium and self._sky_by_bsdf(scene)) if but_sky is None else but_sky
        if dr.hint(sky_by_bsdf and len(scene.emitters()) > 1, mode="scalar"):
            ds, em_w = self._sample_emitter_but_sky(scene, it, sampler.next_2d(active), active)
        else:
            ds, em_w = scene.sample_emitter_direction(it, sampler.next_2d(active), False, active)
        infinite = mi.has_flag(ds.emitter.flags(), mi.EmitterFlags.Infinite)
        if dr.hint(sky_by_bsdf, mode="scalar"):  # the sky alone (or a rounding edge of the remap)
            em_w = dr.select(infinite & ~ds.delta, 0.0, em_w)
        if dr.hint(self.sun_one_minus_cos is not None, mode="scalar"):
            ds.d = self._sun_disk_direction(sampler, ds.d, ds.delta & infinite, active)
        if in_medium:  # a medium vertex: no offset from a surface
            shadow = mi.Ray3f(it.p, ds.d)
            shadow.maxt = dr.select(infinite, dr.inf, ds.dist * (1.0 - 1e-4))
        else:  # spawn_ray moves the origin off the surface by (1 + |p|) eps (~2 mm at 20 m): a light
            # at a finite distance needs spawn_ray_to, which stops short of the light by the same rule
            shadow = dr.select(infinite, it.spawn_ray(ds.d), it.spawn_ray_to(ds.p))
        visible = active & (ds.pdf != 0) & ~scene.ray_test(shadow, active)
        if in_medium:
            f, f_pdf = scatter.eval_pdf(ctx, it, ds.d, active)
        else:
            f, f_pdf = scatter.eval_pdf(ctx, it, it.to_local(ds.d), active)
        Tr = mi.Spectrum(1.0)
        if fog is not None:
            Tr = self._transmittance(fog, ops, it.p, ds.d, dr.select(infinite, ops.largest, ds.dist))
        c = em_w * f
        if tr.has_smooth:  # MIS only matters for emitters a sampled direction can hit
            c *= dr.select(ds.delta, 1.0, mis_weight(ds.pdf, f_pdf))
        return dr.select(visible, c * Tr, 0.0), ds.delta

    def _sample_emitter_but_sky(self, scene, it, u, active):
        """``scene.sample_emitter_direction`` (no visibility test) among the emitters other
        than the constant sky: the selection's CDF with the sky's share cut out, ``u.x``
        stretched over the rest, so an emitter is chosen with probability ``p / (1 - p_sky)``
        and the sun of a sun + sky scene every time.  Returns (ds, weight) with ``ds.pdf``
        the selection probability times the direction's pdf, as Mitsuba's."""
        p_sky, below = self._sky_selection(scene)
        x = u.x * (1.0 - p_sky)
        x = dr.minimum(dr.select(x >= below, x + p_sky, x), 1.0 - 2.0**-24)
        idx, sel_w, x_reuse = scene.sample_emitter(x, active)
        emitter = dr.gather(mi.EmitterPtr, scene.emitters_dr(), idx, active)
        ds, w = emitter.sample_direction(it, mi.Point2f(x_reuse, u.y), active)
        sel_w = sel_w * (1.0 - p_sky)  # 1 / (p / (1 - p_sky))
        ds.pdf = dr.select(sel_w > 0, ds.pdf / sel_w, 0.0)
        return ds, w * sel_w

    def _sun_disk_direction(self, sampler, d, is_sun, active):
        """``d`` (toward the delta sun) replaced on ``is_sun`` lanes by a direction uniform in
        the sun's disk: ``cos = 1 - u (1 - cos theta_max)`` (1 - cos in float64, opaque), a
        uniform azimuth.  The emitter's weight ``E`` is unchanged: radiance ``E / Omega`` over
        pdf ``1 / Omega``."""
        u = sampler.next_2d(active)
        omc = dr.opaque(mi.Float, self.sun_one_minus_cos)
        x = u.x * omc  # 1 - cos
        sin_t = dr.safe_sqrt(x * (2.0 - x))
        s, c = dr.sincos(2.0 * dr.pi * u.y)
        local = mi.Vector3f(c * sin_t, s * sin_t, 1.0 - x)
        return dr.select(is_sun, dr.normalize(mi.Frame3f(d).to_world(local)), d)

    def _sun_disk_seen(self, scene, ops, ray, seen):
        """The sun disk's radiance ``E / Omega`` on the lanes ``seen`` (rays that escape to the sky
        unscattered from the camera) whose direction lies in the disk, 0 on the others; None for a
        delta sun or no sun (trace-time: such scenes trace no code for it).  In the disk:
        ``|d - w|^2 <= 2 (1 - cos theta_max)``, the chord, free of the cancellation of ``1 - d.w``
        in float32."""
        sun = None if self.sun_one_minus_cos is None else self._scene_sun(scene)
        if sun is None:
            return None
        w_sun, E_sun = sun
        omega = 2.0 * math.pi * self.sun_one_minus_cos
        to_sun = mi.Vector3f(*ops.params(w_sun))
        inside = seen & (dr.squared_norm(ray.d - to_sun) <= ops.param(2.0 * self.sun_one_minus_cos))
        return dr.select(inside, mi.Spectrum(*ops.params([e / omega for e in E_sun])), 0.0)

    def _medium_vertex(self, tr, sampler, ray, p, t, med, sun_sampled, closed=True, deferred=False):
        """Light sample and phase sample at the medium vertex ``p`` at distance ``t`` on
        ``ray``, on the lanes ``med``.  Where the sun's scattering is sampled along the segment
        (``tr.sun_along``, on the lanes ``sun_sampled``, a mask or True for every lane) its sun
        NEE is left out (with the residual, not computed).  With
        ``sky_at_media``'s residual (``tr.sky_residual``) next-event estimation samples the other
        emitters, the sky's light is :meth:`_sky_residual_light`, and the phase sample's pdf is 0:
        an escape from the vertex adds no sky (its MIS weight is 0).  ``deferred`` (trace-time): the
        residual's sample is left to the segment the path continues on (:meth:`_sky_on_segment`),
        and the vertex adds the closed form only where ``closed`` (a mask, or True).
        Returns (contribution without the throughput, direction, phase weight, its pdf)."""
        mei = self._medium_interaction(ray, p, t)
        residual = tr.sky_residual is not None
        Ld = mi.Spectrum(0.0)
        if not residual:
            Ld, delta = self._direct(tr, sampler, mei, tr.phase, med)
            if tr.sun_along:  # the sun on this segment is sampled along it
                Ld = dr.select(delta & sun_sampled, 0.0, Ld)
        elif tr.has_delta and not (tr.sun_along and sun_sampled is True):
            # the delta lights alone; where the sun is sampled along the segment it is the only one
            on = (med & ~sun_sampled) if tr.sun_along else med
            Ld = self._direct(tr, sampler, mei, tr.phase, on, but_sky=True)[0]
        wo, w, pdf = tr.phase.sample(tr.phase_ctx, mei, sampler.next_1d(med), sampler.next_2d(med), med)
        if residual:
            if deferred:
                L, B = self._sky_and_below(tr, med)
                Ld += dr.select(med & closed, self._sky_closed_form(tr, ray.d, L, B), 0.0)
            else:
                Ld += self._sky_residual_light(tr, ray, mei.p, wo, w, med)
            pdf = mi.Float(0.0)
        return Ld, wo, w, pdf

    def _sky_residual_light(self, tr, ray, p, wo, w, active):
        """The constant sky's light at the medium vertex ``p`` on ``ray`` (direction ``d``):
        ``L H(d_y) + B (1 - H(d_y)) + w (L V T - c(wo))``.  ``L`` is the sky's radiance (the
        emitter's, a Dr.Jit input), ``H`` the share of the phase lobe around ``d`` above the horizon
        (tabulated, :attr:`SkyResidual.share`), ``wo`` and ``w`` the continuation's phase sample
        and weight, ``V T`` its visibility and transmittance to the sky, and ``c(wo)`` the control
        variate: ``L`` above the horizon, ``B`` (:class:`SkyResidual`) below it.
        ``E[w 1{wo_y > 0}] = H(d_y)``, so the terms besides ``w L V T`` have mean 0: unbiased for
        any geometry and any ``B``.  With an open sky above the horizon, thin fog and a ground
        as bright as ``B`` below it, what is left to sample is near 0."""
        scene, ops = tr.scene, tr.ops
        L, B = self._sky_and_below(tr, active)
        open_ = active & ~scene.ray_test(mi.Ray3f(p, wo), active)
        T = self._transmittance(tr.fog, ops, p, wo, ops.largest)
        light = self._sky_closed_form(tr, ray.d, L, B) + w * self._sky_residual_sample(wo, open_, T, L, B)
        return dr.select(active, light, 0.0)

    @staticmethod
    def _sky_residual_sample(d, open_, T, L, B):
        """``L V T - c(d)``: the residual's sample along the direction ``d`` (without the phase
        weight), ``V`` the mask ``open_`` (nothing hit toward the sky), ``T`` the transmittance to
        the sky, ``c(d)`` ``L`` above the horizon and ``B`` below it."""
        return L * dr.select(open_, T, 0.0) - dr.select(d.y > 0, L, B)

    def _sky_closed_form(self, tr, d, L, B):
        """``L H(d_y) + B (1 - H(d_y))``: the closed-form part of :meth:`_sky_residual_light`'s light
        at a medium vertex on a ray of direction ``d``."""
        H = tr.ops.interp_uniform(d.y, -1.0, 1.0, tr.sky_residual.share)
        return L * H + B * (1.0 - H)

    def _sky_and_below(self, tr, active):
        """``(L, B)``: the constant sky's radiance ``L`` (the emitter's, a Dr.Jit input) and ``B =
        rho (L + sun)``, the surface below the camera lit (:class:`SkyResidual`)."""
        sr = tr.sky_residual
        L = self._constant_sky(tr.scene).eval(dr.zeros(mi.SurfaceInteraction3f), active)  # not read
        return L, mi.Spectrum(*tr.ops.params(sr.rho)) * (L + mi.Spectrum(*tr.ops.params(sr.sun)))

    def _sky_on_segment(self, tr, ray, D, hit, along, residual):
        """What the sky adds on the segment ``[0, D]`` of ``ray`` (``hit``: it ends on a surface),
        as ``(mean, residual)``, each 0 off its lanes.

        ``mean`` (lanes ``along``): the mean of what the segment adds through its end.  That is the
        sky's closed form (:meth:`_sky_closed_form`) at a vertex on it, ``albedo (1 - T(D)) (L
        H(d_y) + B (1 - H(d_y)))`` (``E[w_ff 1{vertex}] = albedo (1 - T(D))`` per channel), and
        where it ends on a surface, with ``surface_control``, the control variate ``B`` its
        surface vertex subtracts, ``T(D) B`` (``E[w_ff 1{surface}] = T(D)``).

        ``residual`` (lanes ``residual``, whose segment leaves a medium vertex along its phase
        sample): that vertex's residual, ``L V T - c(d)`` (:meth:`_sky_residual_light`; the phase
        weight is in the path's throughput).  The segment's own hit is the visibility ``V`` and,
        where it escapes, ``T(D)`` is the transmittance to the sky: no ray or transmittance of its
        own."""
        ops = tr.ops
        L, B = self._sky_and_below(tr, along | residual)
        T = self._transmittance(tr.fog, ops, ray.o, ray.d, D)
        mean = spectrum(ops.params(tr.fog.albedo)) * (1.0 - T) * self._sky_closed_form(tr, ray.d, L, B)
        if self.surface_control:
            mean += dr.select(hit, T * B, 0.0)
        rest = self._sky_residual_sample(ray.d, ~hit, T, L, B)
        return dr.select(along, mean, 0.0), dr.select(residual, rest, 0.0)

    def _surface_vertex(self, tr, sampler, ray, si, surf):
        """Light sample (when the scene has lights; else None) and BSDF sample at the surface
        ``si`` hit by ``ray``, on the lanes ``surf``.  Returns (contribution without the
        throughput, BSDF sample, its weight)."""
        bsdf, Ls = si.bsdf(ray), None
        if tr.has_lights:
            smooth = surf & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
            Ls, _ = self._direct(tr, sampler, si, bsdf, smooth)
        bs, w_b = bsdf.sample(tr.bsdf_ctx, si, sampler.next_1d(surf), sampler.next_2d(surf), surf)
        return Ls, bs, w_b

    # ------------------------------------------------------------- the camera ray
    def _sun_sampler(self, fog, w_sun):
        """(how the sun's single scattering along a ray is sampled: ``"exact"``, ``"mixture"``
        or None, stratified samples per camera ray) in the fog ``fog`` toward the sun ``w_sun``:
        :func:`~fogref.media.single_scatter.sun_sampling_mode` with its defaults (the exact
        sampler for one unbounded exponential layer: for several, its Newton inversion costs
        more time than the variance it removes, ``reports/benchmarks/variance_reduction.md``;
        elsewhere the closed-form mixture) and :data:`SUN_SAMPLES` samples."""
        return sun_sampling_mode(fog, w_sun), SUN_SAMPLES

    def _sun_single_scatter(self, tr, sampler, ray, D, active, samples=None):
        """The sun's single scattering along the ray (the camera ray, or with
        ``sun_sampling_rays`` above 1 a later segment), sampled from its exact
        integrand (``exact``) or a closed-form mixture proposal with the exact
        weight (``mixture``: bounded fog, several layers), the stratified samples of
        :meth:`_sun_sampler` averaged (``samples``, if given, instead; None when it does not
        apply; then NEE covers it)."""
        scene, fog, ops = tr.scene, tr.fog, tr.ops
        sun = self._scene_sun(scene) if (fog is not None and self.sun_sampling) else None
        mode, K = (None, 0) if (sun is None or self.max_depth < 2) else self._sun_sampler(fog._obj, sun[0])
        disk = self.sun_one_minus_cos is not None
        if disk and mode is not None:
            # a sun disk: the exact sampler toward a point of the disk drawn per sample, when the
            # whole disk is above the horizon; otherwise next-event estimation samples it
            sin_radius = math.sqrt(self.sun_one_minus_cos * (2.0 - self.sun_one_minus_cos))
            if mode != "exact" or sun[0][1] <= sin_radius + 1e-6:
                mode = None
        if mode is None:
            return None
        w_sun, E_sun = sun
        K, total = samples or K, mi.Spectrum(0.0)
        for k in range(K):
            channel = self._draw_channel(sampler, active)  # one-sample spectral MIS inside the sampler
            u = (k + sampler.next_1d(active)) / K  # stratified along the integrand's CDF
            to_sun = mi.Vector3f(*ops.params(w_sun))
            w_k = w_sun
            if disk:  # uniform in the disk: the disk's mean of the delta sun's estimator
                to_sun = self._sun_disk_direction(sampler, to_sun, mi.Bool(True), active)
                w_k = (to_sun.x, to_sun.y, to_sun.z)
            if mode == "exact":
                t_ss, w_ss = sample_sun_single_scatter(ops, fog._obj, ray.o, ray.d, D, w_k, E_sun, u, channel)
            else:
                t_ss, w_ss = sample_sun_single_scatter_mixture(
                    ops, fog._obj, ray.o, ray.d, D, w_sun, E_sun, u, sampler.next_1d(active), channel
                )
            vis = active & ~scene.ray_test(mi.Ray3f(ray.o + ray.d * t_ss, to_sun), active)
            total += dr.select(vis, mi.Spectrum(*w_ss), 0.0)
        return total / K

    def _forced_collision(self, tr, sampler, ray, D, active):
        """A medium collision on the camera ray's ``[0, D]`` forced to happen.

        Layer ``i`` is chosen with probability ``(1 - T_i) / sum_j (1 - T_j)``
        (``T_i``: its transmittance over ``[0, D]`` in the sampled channel) and
        inverted in closed form conditioned on a collision before ``D``; the pdf is
        the mixture ``sigma sum_i rho_i T_i(t) / sum_j (1 - T_j(D))`` (one layer:
        ``sigma_t T / (1 - T)``), averaged over the channels (one-sample spectral
        MIS for this segment).  Returns (t, weight ``sigma_s T(t) / pdf``, valid).
        Height layers only (fogpath uses free flight instead with a Local Fog Volume).
        """
        fog, ops = tr.fog, tr.ops
        fog.require_height_only("fogpath's forced collision")
        t0, t1 = (mi.Float(0.0), ops.largest) if fog.bounds is None else fog.clip(ops, ray.o, ray.d)
        t_end = dr.minimum(D, t1)
        length = dr.maximum(t_end - t0, 0.0)
        t0 = dr.select(length > 0, t0, 0.0)
        oy, dy = ray.o.y + t0 * ray.d.y, ray.d.y
        om = lambda x: dr.select(x < 1e-4, x * (1.0 - 0.5 * x), 1.0 - dr.exp(-x))  # noqa: E731  1 - e^-x
        tau_D = [dr.minimum(L.depth(ops, oy, dy, length), cf.TAU_MAX) for L in fog.layers]
        sig_rgb, alb_rgb = ops.params(fog.sigma_t), ops.params(fog.albedo)
        sig = sig_rgb[0]
        grey = fog.sigma_t[1] == fog.sigma_t[0] and fog.sigma_t[2] == fog.sigma_t[0]
        if not grey:
            channel = self._draw_channel(sampler, active)
            sig = dr.select(channel == 1, sig_rgb[1], dr.select(channel == 2, sig_rgb[2], sig))
        u = sampler.next_1d(active)
        oms = [om(sig * tau) for tau in tau_D]
        t_rel = fog.layers[0].sample(ops, oy, dy, -dr.log(1.0 - u * oms[0]) / sig)
        if len(fog.layers) > 1:
            pick, acc = sampler.next_1d(active) * sum(oms), mi.Float(0.0)
            for L, o_i in zip(fog.layers, oms):
                t_i = L.sample(ops, oy, dy, -dr.log(1.0 - u * o_i) / sig)
                t_rel = dr.select((pick >= acc) & (o_i > 0), t_i, t_rel)
                acc += o_i
        valid = active & (length > 0) & (t_rel < ops.largest) & (sum(oms) > 0)
        t_rel = dr.minimum(dr.select(valid, t_rel, 0.0), length)
        tau_t = [dr.minimum(L.depth(ops, oy, dy, t_rel), cf.TAU_MAX) for L in fog.layers]
        rho_t = [L.rho(ops, oy + t_rel * dy) for L in fog.layers]
        pdfs, fs = [], []
        for s, a in zip(sig_rgb, alb_rgb):
            norm = sum(om(s * tau) for tau in tau_D)
            pdfs.append(
                s * sum(r * dr.exp(-s * tau) for r, tau in zip(rho_t, tau_t)) / dr.maximum(norm, 1e-30)
            )
            fs.append(a * s * sum(rho_t) * dr.exp(-s * sum(tau_t)))
        pdf = pdfs[0] if grey else (pdfs[0] + pdfs[1] + pdfs[2]) / 3.0
        w = dr.select(valid & (pdf > 0), spectrum(fs) / pdf, 0.0)
        return t0 + t_rel, w, valid & (pdf > 0)

    def _camera_light(self, tr, sampler, ray, si, active):
        """The surface branch's light at depth 0, without the camera segment's weight ``T``:
        the emitter the camera ray hits (the sky too, unless ``hide_emitters``), the sun disk it
        sees and the light sample at the surface ``si`` it hits (one sampler draw set)."""
        scene, ops, hit = tr.scene, tr.ops, si.is_valid()
        direct = mi.Spectrum(0.0)
        if tr.has_smooth:
            em = active & (hit if self.hide_emitters else mi.Bool(True))
            ds = mi.DirectionSample3f(scene, si=si, ref=dr.zeros(mi.Interaction3f))
            direct += dr.select(em, ds.emitter.eval(si, em), 0.0)
        disk = None if self.hide_emitters else self._sun_disk_seen(scene, ops, ray, active & ~hit)
        if disk is not None:  # the sun disk the camera ray sees
            direct += disk
        bsdf = si.bsdf(ray)
        smooth = active & hit & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        return direct + self._direct(tr, sampler, si, bsdf, smooth)[0]

    def _camera_split(self, tr, sampler, ray, si, D, active):
        """Depth 0 with ``forced_split``: the surface branch (light found by the camera
        ray, light sample at the surface, :meth:`_camera_light`; weight ``T`` applied at the
        end), then :meth:`_continuation`: the surface's BSDF sample, a forced medium vertex
        (its light sample feeds ``single``) and one branch continued.  Returns (the :class:`Path` from
        depth 1, the :class:`Cover`).  ``surface_coverage`` is 1 on samples that continued the
        surface branch (for the sky: drew it with the same q) and ``surface`` their unweighted
        light, so that ``surface`` stays a ratio estimator bounded by the radiance it estimates."""
        T = self._transmittance(tr.fog, tr.ops, ray.o, ray.d, D)
        direct = self._camera_light(tr, sampler, ray, si, active)
        path, chose_s, q, ld = self._continuation(tr, sampler, ray, si, D, T, active)
        path.split = Split(direct).add(ld, mi.Bool(True), mi.Bool(True))
        return path, Cover(chose_s, direct, dr.select(si.is_valid(), q, 1.0))

    def _continuation(self, tr, sampler, ray, si, D, T, active, bsdf_first=True, surface_slot=None):
        """Forced splitting after the camera ray's surface branch: a medium collision on its
        ``[0, D]`` forced to happen (:meth:`_forced_collision`) with its light sample, then one
        branch continues, the surface (hit ``si``) or the medium, chosen with probability
        ``q = T / (T + w_medium w_phase)`` (means over RGB; weight ``1/q`` or ``1/(1 - q)``).

        ``bsdf_first``: the surface's BSDF sample is drawn before the forced collision (fogpath),
        or after its medium vertex (false: the benchmarks' order).  ``surface_slot``
        (a mask; the benchmarks' continuation splitting, ``benchmarks/_fogpath_knobs.py``): no
        branch drawn, the lanes on it that hit a surface continue the surface branch, the others
        the medium branch, without the ``1/q``, ``1/(1 - q)`` weights.  Both are Python-level
        choices: the defaults trace fogpath's kernel.  Returns (the :class:`Path` from depth 1,
        with an empty :class:`Split`; the lanes that continued the surface branch; ``q``; the
        forced collision's light sample times its weight, which feeds ``single``)."""
        hit = si.is_valid()
        surf = active & hit
        bsdf = si.bsdf(ray)
        draw = lambda: bsdf.sample(tr.bsdf_ctx, si, sampler.next_1d(surf), sampler.next_2d(surf), surf)  # noqa: E731
        bsdf_sample = draw() if bsdf_first else None
        t_m, w_m, med = self._forced_collision(tr, sampler, ray, D, active)
        p_med = ray.o + ray.d * t_m
        Ld, wo_m, w_ph, pdf_m = self._medium_vertex(tr, sampler, ray, p_med, t_m, med, True)
        # q = T / (T + w_medium) >= T: it must not depend on the surface branch's own samples
        # (the ratio estimator `surface` keeps the samples that continued it), and q >= T
        # keeps `surface` defined wherever the old scatter-or-reach choice defined it.
        # A ray to the sky has no surface to continue: it always continues the medium and
        # its q only draws surface_coverage, so that `surface` is undefined where T ~ 0.
        ms = dr.mean(T)
        mm = dr.select(med, dr.mean(w_m * w_ph), 0.0)
        q = dr.select(ms + mm > 0, ms / (ms + mm), 0.0)  # probability of continuing the surface branch
        bs, w_b = bsdf_sample if bsdf_first else draw()
        if surface_slot is None:
            chose_s = sampler.next_1d(active) < q
            go_s = surf & chose_s
            go_m = med & dr.select(hit, ~chose_s & (q < 1), True)
            β = dr.select(go_s, w_b / q, dr.select(go_m, w_m * w_ph / dr.select(hit, 1.0 - q, 1.0), 0.0))
        else:
            chose_s = surface_slot & hit
            go_s, go_m = surf & chose_s, med & ~chose_s
            β = dr.select(go_s, w_b, dr.select(go_m, w_m * w_ph, 0.0))
        prev_it = self._vertex(ray, si, go_s, p_med)
        ray = dr.select(
            go_s, si.spawn_ray(si.to_world(bs.wo)), mi.Ray3f(p_med, wo_m, ray.time, ray.wavelengths)
        )
        act = (go_s | go_m) & (dr.max(β) > 0) & (self.max_depth > 1)
        path = Path(ray, tr.scene.ray_intersect(ray, act), act, depth=1)
        path.β_cam, path.β, path.medium_first = T, β, go_m
        path.prev_it, path.prev_pdf = prev_it, dr.select(go_s, bs.pdf, pdf_m)
        path.prev_delta = go_s & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        return path, chose_s & active, q, dr.select(med, w_m * Ld, 0.0)

    def _camera_hit(self, tr, sampler, ray, active):
        """The camera ray's hit ``si``, its distance ``D`` (``ops.largest`` to the sky), its
        G-buffer (None without ``aovs``) and the sun's single scattering sampled along it (None
        where next-event estimation covers it; sets ``tr.sun_along``)."""
        si = tr.scene.ray_intersect(ray, active)
        D0 = dr.select(si.is_valid(), si.t, tr.ops.largest)
        gbuf = self._gbuffer(tr.fog, tr.ops, ray, si) if self.aovs else None
        sun_ss = self._sun_single_scatter(tr, sampler, ray, D0, active)
        tr.sun_along = sun_ss is not None
        return si, D0, gbuf, sun_ss

    def _splits(self, tr):
        """Does the camera ray take forced splitting: ``forced_split``, a scattering fog without a
        Local Fog Volume (free flight there: the forced collision covers height layers only),
        lights, ``max_depth >= 2`` (trace-time)."""
        forced = self.forced_split and (tr.fog is None or tr.fog.volume is None)
        return tr.phase is not None and tr.has_lights and forced and self.max_depth >= 2

    def _camera_ray(self, tr, sampler, ray, active):
        """The camera ray's stage: its hit, G-buffer and the sun's single scattering sampled
        along it (:meth:`_camera_hit`), and with forced splitting (:meth:`_splits`) both of its
        branches (:meth:`_camera_split`).  Returns the :class:`CameraRay`; its ``path`` starts
        at depth 1 after forced splitting, else at depth 0 on the camera ray (the loop then
        traces the camera ray's free flight)."""
        si, D0, gbuf, sun_ss = self._camera_hit(tr, sampler, ray, active)
        active = active & tr.has_lights  # no emitter: nothing to trace beyond the G-buffer
        if self._splits(tr):
            path, cover = self._camera_split(tr, sampler, ray, si, D0, active)
            return CameraRay(gbuf, sun_ss, cover, path)
        return CameraRay(gbuf, sun_ss, None, Path(ray, si, active))

    def _gbuffer(self, fog, ops, ray, si):
        """T, coverage-independent G-buffer of the camera ray (closed form, per sample)."""
        hit = si.is_valid()
        T = mi.Spectrum(1.0)
        if fog is not None:
            T = self._transmittance(fog, ops, ray.o, ray.d, dr.select(hit, si.t, ops.largest))
        return {
            "T": [T[0], T[1], T[2]],
            "distance": [dr.select(hit, si.t, 0.0)],
            "P": [dr.select(hit, si.p[i], 0.0) for i in range(3)],
            "view": [ray.d[i] for i in range(3)],
            "hit": [dr.select(hit, 1.0, 0.0)],
        }

    # ----------------------------------------------------------------- sample
    def _tracing(self, scene, sampler):
        """The :class:`Trace` of a ``sample`` call on ``scene`` (trace-time)."""
        fog = self._scene_fog(scene)
        has_delta, has_smooth = self._scene_lights(scene)
        phase = (
            scene.sensors()[0].get_medium().phase_function() if (fog is not None and fog.scatters) else None
        )
        return Trace(scene, fog, phase, sampler, has_delta, has_smooth, self._sky_residual(scene))

    def sample(self, scene, sampler, ray, medium=None, active=True):
        tr = self._tracing(scene, sampler)
        active = mi.Bool(active)
        cam = self._camera_ray(tr, sampler, mi.Ray3f(ray), active)
        split, β_cam, medium_first = self._trace(tr, sampler, cam.path)
        if tr.sun_along:  # the camera ray's sampled sun scattering
            split = Split(split.surface, split.single + dr.select(active, cam.sun_ss, 0.0), split.multiple)
        # surface, surface_coverage: the camera ray reached the surface unscattered, or with forced
        # splitting the sample continued the surface branch: its light is then the depth-0 part
        # plus the continuation without the 1/q weight
        covered, s_out = ~medium_first, split.surface
        if cam.cover is not None:
            c = cam.cover
            covered, s_out = c.chosen, c.direct + c.q * (split.surface - c.direct)
        coverage, surface = dr.select(covered, 1.0, 0.0), dr.select(covered, s_out, 0.0)
        return self._outputs(split, β_cam, cam.gbuf, coverage, surface)

    @dr.syntax
    def _trace(self, tr, sampler, p):
        """The path loop, from the :class:`Path` ``p`` (on the camera ray at depth 0, or at depth 1
        after forced splitting) until every lane has ended: free flight, emission found, light
        and direction samples at medium and surface vertices, Russian roulette.  Returns (the
        parts so far plus the path's, a :class:`Split`; the camera segment's weight ``β_cam``;
        whether the camera ray scattered first)."""
        scene, phase, has_smooth, ops = tr.scene, tr.phase, tr.has_smooth, tr.ops
        split, β, β_cam, depth, medium_first = p.split, p.β, p.β_cam, p.depth, p.medium_first
        ray, si, active = p.ray, p.si, p.active
        prev_it, prev_pdf, prev_delta = p.prev_it, p.prev_pdf, p.prev_delta
        # the sun along segments after the camera ray, up to sun_sampling_rays (a segment's vertex
        # scatters only when depth + 1 < max_depth: the depth-1 segment's when max_depth >= 3)
        ss_next = tr.sun_along and self.sun_sampling_rays >= 2 and self.max_depth >= 3
        along = tr.sky_residual is not None and self.sky_along_segments
        pending = mi.Bool(False)  # the segment leaves a medium vertex whose residual it samples
        while dr.hint(active, max_iterations=-1, label="fogpath"):
            if dr.hint(ss_next, mode="scalar"):
                on = active & (depth >= 1) & (depth < self.sun_sampling_rays) & (depth + 1 < self.max_depth)
                D1 = dr.select(si.is_valid(), si.t, ops.largest)
                ss1 = self._sun_single_scatter(tr, sampler, ray, D1, on, samples=1)
                split = split.add(dr.select(on, β * ss1, 0.0), medium_first, mi.Bool(False))
            if dr.hint(along, mode="scalar"):  # the sky on segments after the camera ray
                on = active & (depth >= 1) & (depth + 1 < self.max_depth)
                hit = si.is_valid()
                D1 = dr.select(hit, si.t, ops.largest)
                mean, rest = self._sky_on_segment(tr, ray, D1, hit, on, active & pending)
                split = split.add(β * mean, medium_first, mi.Bool(False))
                split = split.add(β * rest, medium_first, depth == 1)  # the last vertex's residual
            # ---------------- free flight to a medium vertex or the surface ----------------
            is_medium, t_end, w_ff = self._free_flight(
                tr, sampler, ray, dr.select(si.is_valid(), si.t, dr.inf), active
            )
            passed = active & (depth == 0) & ~is_medium
            medium_first |= active & (depth == 0) & is_medium
            β_cam[passed] = w_ff
            β[active & ~passed] *= w_ff
            is_surface, escaped = active & ~is_medium & si.is_valid(), active & ~is_medium & ~si.is_valid()

            # ---------------- emission found by the last sampled direction ----------------
            if dr.hint(has_smooth, mode="scalar"):
                em = is_surface | escaped
                if dr.hint(self.hide_emitters, mode="scalar"):
                    em &= ~((depth == 0) & escaped)
                ds = mi.DirectionSample3f(scene, si=si, ref=prev_it)
                em_pdf = scene.pdf_emitter_direction(prev_it, ds, em & ~prev_delta)
                if dr.hint(self._sky_by_bsdf(scene), mode="scalar"):  # from a surface: the sky at weight 1,
                    from_surface = dr.squared_norm(prev_it.n) > 0  # other lights as _sample_emitter_but_sky
                    p_sky = self._sky_selection(scene)[0]
                    other = em_pdf / (1.0 - p_sky) if p_sky < 1.0 else em_pdf  # p_sky 1: the sky alone
                    em_pdf = dr.select(from_surface, dr.select(escaped, 0.0, other), em_pdf)
                Le = β * mis_weight(prev_pdf, dr.select(prev_delta, 0.0, em_pdf)) * ds.emitter.eval(si, em)
                split = split.add(dr.select(em, Le, 0.0), medium_first, depth == 1)
            seen = escaped & (depth == 0)
            disk = None if self.hide_emitters else self._sun_disk_seen(scene, ops, ray, seen)
            if disk is not None:  # the sun disk a camera ray sees (next-event estimation has the rest)
                split = split.add(β * disk, medium_first, mi.Bool(False))
            active &= ~escaped & (depth + 1 < self.max_depth)  # max_depth = 2: single scattering

            # ---------------- medium vertex: light sample, phase sample ----------------
            p_med = ray.o + ray.d * dr.select(is_medium, t_end, 0.0)
            med = active & is_medium
            wo, pdf_next, delta_next, w_next, origin = (
                mi.Vector3f(ray.d),
                mi.Float(1.0),
                mi.Bool(False),
                mi.Spectrum(1.0),
                mi.Point3f(p_med),
            )
            if dr.hint(phase is not None and tr.has_lights, mode="scalar"):
                sun_sampled = (depth < self.sun_sampling_rays) if ss_next else (depth == 0)
                closed = (depth == 0) if along else True
                Ld, wo_m, w_m, pdf_m = self._medium_vertex(
                    tr, sampler, ray, p_med, t_end, med, sun_sampled, closed, deferred=along
                )
                pending = mi.Bool(med)
                split = split.add(β * Ld, medium_first, depth == 0)
                wo[med], pdf_next[med], w_next[med] = wo_m, pdf_m, w_m

            # ---------------- surface vertex: light sample, BSDF sample ----------------
            surf = active & is_surface
            if dr.hint(along and self.surface_control, mode="scalar"):  # _sky_on_segment added its mean
                below = -β * self._sky_and_below(tr, surf)[1]
                split = split.add(dr.select(surf & (depth >= 1), below, 0.0), medium_first, mi.Bool(False))
            Ls, bs, w_b = self._surface_vertex(tr, sampler, ray, si, surf)
            if dr.hint(Ls is not None, mode="scalar"):
                split = split.add(β * Ls, medium_first, mi.Bool(False))
            wo[surf], pdf_next[surf], w_next[surf], origin[surf] = si.to_world(bs.wo), bs.pdf, w_b, si.p
            delta_next[surf] = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)

            # ---------------- next segment, Russian roulette ----------------
            prev_it = self._vertex(ray, si, surf, p_med)
            prev_pdf, prev_delta = pdf_next, delta_next
            β *= w_next
            ray = dr.select(surf, si.spawn_ray(wo), mi.Ray3f(origin, wo, ray.time, ray.wavelengths))
            depth[active] += 1
            active &= dr.max(β) > 0
            rr = active & (depth >= self.rr_depth)
            q = dr.minimum(dr.max(β), 0.95)
            β[rr] *= dr.rcp(q)
            active &= ~rr | (sampler.next_1d(rr) < q)
            si = scene.ray_intersect(ray, active)
        return split, β_cam, medium_first

    # ------------------------------------------------------------- outputs
    def _outputs(self, split, β_cam, gbuf, coverage, surface):
        """(L, valid, AOVs) in the order of :data:`AOV_NAMES`, from the parts ``split``, the camera
        segment's weight ``β_cam`` (``attenuated_surface = β_cam surface``), the G-buffer (None:
        no AOVs) and the sample's ``surface_coverage`` (in [0, 1]) and ``surface``."""
        att = β_cam * split.surface
        L = att + split.single + split.multiple
        if gbuf is None:
            return L, mi.Bool(True), []
        rgb = lambda s: [s[0], s[1], s[2]]  # noqa: E731
        parts = {
            "attenuated_surface": rgb(att),
            "inscatter": rgb(split.single + split.multiple),
            "single": rgb(split.single),
            "multiple": rgb(split.multiple),
            "surface": rgb(surface),
            "surface_coverage": [coverage],
            **gbuf,
        }
        return L, mi.Bool(True), [c for g in gbuffer.SAMPLE_GROUPS for c in parts[g]]

    # ------------------------------------------------------------- render
    def render_moments(self, scene, sensor=0, seed=0, spp=1, pixel_exact=None, squares=True):
        """Per-pixel sums of every per-sample output and of the squares of the parts.

        Returns ``(sums, squares)``: float64 ``TensorXd`` of shape ``(H, W, 3 + len(AOV_NAMES))``
        (R,G,B then :data:`AOV_NAMES`) and ``(H, W, 6 * len(gbuffer.SQUARED_GROUPS))``,
        summed over the ``spp`` samples of each pixel: the squares of every channel of
        :data:`~fogref.gbuffer.SQUARED_GROUPS`, then the products of their channel pairs
        :data:`~fogref.gbuffer.CHANNEL_PAIRS` (R*G, R*B, G*B; the noise correlations).
        With ``aovs`` off: R,G,B, their squares and products only.  ``squares=False``: the
        second is None (not computed).
        ``pixel_exact`` (default: the plugin's property) puts every sample at the
        pixel centre; otherwise samples are uniform in the pixel (box filter).
        Camera rays start at the camera and have no far limit.
        """
        pixel_exact = self.pixel_exact if pixel_exact is None else bool(pixel_exact)
        make_scene_values_opaque(scene)  # one kernel for every value of the scene's parameters
        drjit_ops().trim_params()  # between traces, so that the cache's bound is not met inside one
        self._memo = _Held(scene, {})  # the scene values read while tracing: once (_read_once)
        try:
            with dr.scoped_set_flag(dr.JitFlag.OptimizeLoops, OPTIMIZE_LOOPS):
                sensor = self._checked_sensor(scene, sensor)
                seed_o = dr.opaque(mi.UInt32, int(seed))  # opaque: a new seed needs no new kernel
                args = (scene, sensor, seed_o, int(spp), pixel_exact, squares)
                return self._frozen.run(self, *args) if self.freeze else self._pass(*args)
        finally:
            self._memo = None

    @staticmethod
    def _checked_sensor(scene, sensor):
        """The sensor (an index into ``scene.sensors()`` or the sensor), checked: perspective
        only; a reconstruction filter other than box is replaced by a box filter (warned)."""
        sensor = scene.sensors()[sensor] if isinstance(sensor, int) else sensor
        if not str(sensor).startswith("PerspectiveCamera"):
            raise ValueError(
                f"fogpath renders from a 'perspective' sensor only, not {str(sensor).split('[')[0]}"
            )
        if not sensor.film().rfilter().is_box_filter():
            mi.Log(
                mi.LogLevel.Warn,
                "fogpath: the film's reconstruction filter is replaced by a box filter "
                "(each sample counts in its own pixel)",
            )
        return sensor

    def _fingerprint(self, scene, sensor, spp, pixel_exact, squares):
        """Every Python value a pass's trace reads, as a hashable value compared by equality
        (floats as ``float.hex``, so that -0.0 differs from 0.0): the fog object's fields
        (layers, bounds, phase table, Local Fog Volume), the sun's direction and irradiance,
        the constant sky and its selection pdfs, the integrator's settings, the film's size,
        ``spp``, the pass's options, the scene's emitters and the variant.  Reads (and keeps
        for the call, :meth:`_read_once`) the scene values the trace would read."""
        fog = self._scene_fog(scene)
        sky = self._constant_sky(scene)
        medium = scene.sensors()[0].get_medium() if scene.sensors() else None
        phase = medium.phase_function() if medium is not None else None
        settings = {k: v for k, v in vars(self).items() if not k.startswith("_")}
        settings["hide_emitters"] = self.hide_emitters  # a C++ property of the integrator
        return _plain(
            (
                mi.variant(),
                id(scene),
                [e.class_name() for e in scene.emitters()],
                len(scene.shapes()),
                None if fog is None else fog._obj,
                None if phase is None else phase.class_name(),
                self._scene_sun(scene),
                None if sky is None else (scene.emitters().index(sky), self._sky_selection(scene)),
                self._sky_residual(scene),
                settings,
                list(sensor.film().crop_size()),
                sensor.sampler().class_name(),
                spp,
                pixel_exact,
                squares,
            )
        )

    def _fog_tables(self, scene) -> dict:
        """The arrays of the scene's interpolation tables (a tabulated phase function's cosines
        and values; with ``sky_at_media``'s residual, the phase lobe's share above the horizon),
        made before a recording, which takes them as inputs."""
        fog = self._scene_fog(scene)
        phase = None if fog is None else fog.phase
        columns = (phase.cosines, phase.values) if hasattr(phase, "cosines") else ()
        sky = self._sky_residual(scene)
        return drjit_ops().tables(*columns, *(() if sky is None else (sky.share,)))

    def _pass_reading(self, tables, scene, sensor, seed, spp, pixel_exact, squares):
        """:meth:`_pass` with Dr.Jit's parameter cache holding only ``tables`` (what a recording
        reads: :meth:`fogref.media.ops.DrJitOps.isolated_params`)."""
        with drjit_ops().isolated_params(tables):
            return self._pass(scene, sensor, seed, spp, pixel_exact, squares)

    def _pass(self, scene, sensor, seed, spp, pixel_exact, squares):
        """One pass (``render_moments`` after its checks): ``seed`` an opaque ``UInt32``."""
        film = sensor.film()
        size = film.crop_size()
        n_pix = int(dr.prod(size))
        sampler = sensor.sampler().clone()
        sampler.set_sample_count(spp)
        sampler.set_samples_per_wavefront(spp)
        sampler.seed(seed, n_pix * spp)

        idx = dr.arange(mi.UInt32, n_pix * spp) // dr.opaque(mi.UInt32, spp)
        pos = mi.Vector2u(0)
        pos.y = idx // size[0]
        pos.x = idx - pos.y * size[0]
        pos_f = mi.Vector2f(pos) + (mi.Vector2f(0.5) if pixel_exact else sampler.next_2d())
        ray, weight = sensor.sample_ray(
            sensor.shutter_open(), 0.5, pos_f / mi.ScalarVector2f(size), mi.Point2f(0.5)
        )
        ray = mi.Ray3f(
            sensor.world_transform().translation(), ray.d, ray.time, ray.wavelengths
        )  # no clip planes
        L, _, aovs = self.sample(scene, sampler, ray, None, True)
        L = L * weight
        values = [L[0], L[1], L[2]] + list(aovs)
        names = ["R", "G", "B"] + (AOV_NAMES if self.aovs else [])
        groups = (gbuffer.SQUARED_GROUPS if self.aovs else ("final",)) if squares else ()
        products = [(names.index(c), names.index(c)) for g in groups for c in gbuffer.channel_names(g)]
        products += [
            (names.index(gbuffer.channel_names(g)[i]), names.index(gbuffer.channel_names(g)[j]))
            for g in groups
            for i, j in gbuffer.CHANNEL_PAIRS
        ]
        dr.eval(values)  # one kernel for every output; otherwise each per-pixel sum re-runs the path loop
        sums, sq = self._per_pixel_sums(values, products, n_pix, spp)
        shape = (size[1], size[0], 1)
        sums = dr.concat([mi.TensorXd(a, shape=shape) for a in sums], axis=2)
        sq = dr.concat([mi.TensorXd(a, shape=shape) for a in sq], axis=2) if squares else None
        dr.eval(sums, sq)
        return sums, sq

    @staticmethod
    def _per_pixel_sums(values, products, n_pix, spp):
        """Per-pixel float64 sums of ``values`` (evaluated per-sample arrays, lane
        ``p * spp + s``) and of the products ``values[j] * values[k]`` for ``(j, k)`` in
        ``products`` (squares where ``j == k``): two lists of ``n_pix`` arrays.

        One kernel: a loop over the ``spp`` samples of every pixel, each iteration
        gathering the sample from every output, in a fixed order (deterministic,
        unlike atomic scatter-adds).  Float64 throughout: a float32 square and sum
        would leave a spurious stderr of ~3e-4 x the value.
        """
        spp_o = dr.opaque(mi.UInt32, spp)  # opaque: one kernel for every spp
        first = dr.arange(mi.UInt32, n_pix) * spp_o
        zeros = lambda k: tuple(dr.zeros(mi.Float64, n_pix) for _ in range(k))  # noqa: E731

        def body(s, sums, squares):
            x = [mi.Float64(v if dr.width(v) == 1 else dr.gather(type(v), v, first + s)) for v in values]
            return (
                s + 1,
                tuple(a + b for a, b in zip(sums, x)),
                tuple(
                    a + (dr.square(x[j]) if j == k else x[j] * x[k]) for a, (j, k) in zip(squares, products)
                ),
            )

        _, sums, squares = dr.while_loop(
            (mi.UInt32(0), zeros(len(values)), zeros(len(products))),
            lambda s, sums, squares: s < spp_o,
            body,
            label="fogpath_pixel_sums",
        )
        dr.eval(sums, squares)  # all at once: one loop kernel (read separately, each would re-run the loop)
        return list(sums), list(squares)

    def render(self, scene, sensor=0, seed=0, spp=0, develop=True, evaluate=True):
        """``mi.render``: the per-pixel mean of R,G,B and the AOVs (box filter, or
        pixel-exact with ``pixel_exact``), a ``TensorXf`` ``(H, W, 3 + len(aov_names()))``.
        The ``surface.*`` AOVs are per-sample means here;
        :func:`fogref.gbuffer.moments_to_channels` turns them into the EXR's ratio estimator.

        In passes of at most :data:`fogref_plugins.passes.MAX_LANES` lanes, as the render
        driver does (one pass keeps ``seed``; several are seeded with ``pass_seed``):
        each pass holds every sample's outputs in memory, so one call at 1920x1080 and
        1024 spp would otherwise need ~425 GB."""
        sensor = scene.sensors()[sensor] if isinstance(sensor, int) else sensor
        spp = int(spp) if int(spp) > 0 else sensor.sampler().sample_count()
        passes = pass_sizes(int(dr.prod(sensor.film().crop_size())), spp, max_lanes(mi.variant()))
        total = None
        for k, n in enumerate(passes):
            sums, _ = self.render_moments(
                scene, sensor, seed if len(passes) == 1 else pass_seed(seed, k), n, squares=False
            )
            total = sums if total is None else total + sums
            dr.eval(total)
        return mi.TensorXf(total / spp)


def register() -> None:
    mi.register_integrator("fogpath", lambda props: FogPathIntegrator(props))


__all__ = ["AOV_NAMES", "FogPathIntegrator", "register"]

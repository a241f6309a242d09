"""The plumbing under fogpath's estimator, as Mitsuba's ``common.py`` sits under ``prb.py``.

:class:`FogPathBase` is a ``mi.SamplingIntegrator`` that leaves ``sample`` to its
subclass (:class:`fogref_plugins.fogpath.FogPathIntegrator`) and gives it:

* the scene facts the estimator reads at trace time: the sensor's fog, the kinds of
  light, the sun (:meth:`FogPathBase._scene_fog`, ``_scene_lights``, ``_scene_sun``), the
  values among them read once per render;
* opaque scene values (:func:`make_scene_values_opaque`), so that kernels are reused
  across scenes that differ only in a value;
* the parts of the schema a contribution feeds (:class:`Split`) and the per-sample
  outputs in the order of :data:`AOV_NAMES` (``FogPathBase._outputs``);
* per-pixel moments of every per-sample output (:meth:`FogPathBase.render_moments`),
  what the render driver writes as means and standard errors, and ``mi.render`` in
  passes of at most :data:`fogref_plugins.passes.MAX_LANES` lanes.

The subclass sets ``aovs`` (bool: write :data:`AOV_NAMES` after R,G,B) and
``pixel_exact`` (bool: every sample through the pixel's centre).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
from fogref_plugins.passes import max_lanes, pass_seed, pass_sizes

from fogref import gbuffer

#: The integrator's AOVs (after R,G,B): the per-sample groups of the schema.
AOV_NAMES = gbuffer.sample_channel_names()

#: Dr.Jit's ``OptimizeLoops`` while fogpath traces a pass.  On, Dr.Jit traces every symbolic
#: loop body twice to drop loop-invariant state; off, once.  Off: about 20 ms less host time
#: per pass, pixels bitwise equal and execution time unchanged within noise
#: (``reports/benchmarks/host_time.md``).
OPTIMIZE_LOOPS = False


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


class FogPathBase(mi.SamplingIntegrator):
    """A sampling integrator whose ``sample`` returns R,G,B and :data:`AOV_NAMES` per sample,
    rendered as per-pixel moments (see module)."""

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
        if memo is None or memo[0] is not scene:
            return read()
        if name not in memo[1]:
            memo[1][name] = read()
        return memo[1][name]

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

    # ------------------------------------------------------------- interactions
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

    # ------------------------------------------------------------- outputs
    def _outputs(self, split, β_cam, medium_first, cam, gbuf):
        """(L, valid, AOVs) in the order of :data:`AOV_NAMES`.  ``surface`` and
        ``surface_coverage``: the camera ray reached the surface unscattered, or with
        forced splitting (``cam``) the sample continued the surface branch; its light is
        then the depth-0 part plus the continuation without the 1/q weight."""
        att = β_cam * split.surface
        cover, s_out = ~medium_first, split.surface
        if cam is not None:
            cover, direct, q = cam
            s_out = direct + q * (split.surface - direct)
        L = att + split.single + split.multiple
        if gbuf is None:
            return L, mi.Bool(True), []
        rgb = lambda s: [s[0], s[1], s[2]]  # noqa: E731
        parts = {
            "attenuated_surface": rgb(att),
            "inscatter": rgb(split.single + split.multiple),
            "single": rgb(split.single),
            "multiple": rgb(split.multiple),
            "surface": rgb(dr.select(cover, s_out, 0.0)),
            "surface_coverage": [dr.select(cover, 1.0, 0.0)],
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
        self._memo = (scene, {})  # the scene values read while tracing: once (_read_once)
        try:
            with dr.scoped_set_flag(dr.JitFlag.OptimizeLoops, OPTIMIZE_LOOPS):
                return self._render_moments(scene, sensor, seed, spp, pixel_exact, squares)
        finally:
            self._memo = None

    def _render_moments(self, scene, sensor, seed, spp, pixel_exact, squares):
        sensor = scene.sensors()[sensor] if isinstance(sensor, int) else sensor
        if not str(sensor).startswith("PerspectiveCamera"):
            raise ValueError(
                f"fogpath renders from a 'perspective' sensor only, not {str(sensor).split('[')[0]}"
            )
        film = sensor.film()
        if not film.rfilter().is_box_filter():
            mi.Log(
                mi.LogLevel.Warn,
                "fogpath: the film's reconstruction filter is replaced by a box filter "
                "(each sample counts in its own pixel)",
            )
        size = film.crop_size()
        n_pix, spp = int(dr.prod(size)), int(spp)
        sampler = sensor.sampler().clone()
        sampler.set_sample_count(spp)
        sampler.set_samples_per_wavefront(spp)
        sampler.seed(dr.opaque(mi.UInt32, int(seed)), n_pix * spp)  # opaque: a new seed needs no new kernel

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

"""``fogpath``: a path tracer for exact height fog, in Python with Dr.Jit loops.

The estimator, :class:`FogPathIntegrator` (parameters in its docstring).  Beside it, as
Mitsuba's ``common.py`` beside ``prb.py``: the plumbing (scene facts, opaque values, the
parts and AOVs, per-pixel moments, passes) in :mod:`fogref_plugins.fogpath_common`, and
the camera ray's variance reduction in :mod:`fogref_plugins.fogpath_camera`.  It has:

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
* **the parts of the schema** per sample (:class:`~fogref_plugins.fogpath_common.Split`):
  ``L = attenuated_surface + single + multiple`` exactly.  How the parts, forced
  splitting and the sun's sampling fit together: ``docs/design.md``, "fogpath".

Not supported: sensors other than ``perspective``; media attached to shapes
(the fog fills all space outside surfaces); reconstruction filters other than
box (a warning says so); differentiation.

References: Novák et al., "Monte Carlo methods for volumetric light transport
simulation", Computer Graphics Forum 37(2), 2018 (free-flight sampling, spectral
MIS); Mitsuba 3, ``src/python/python/ad/integrators/prb.py`` (loop structure).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
from mitsuba.python.ad.integrators.common import mis_weight  # the module set_variant loaded (not a 2nd copy)

from fogref import params
from fogref.media import drjit_ops
from fogref.scene.vocabulary import MAX_DEPTH

from .fogpath_camera import FogPathCameraRay
from .fogpath_common import AOV_NAMES, Split, spectrum

#: ``forced_split``'s default (see ``reports/benchmarks/variance_reduction_changes.md``)
FORCED_SPLIT_DEFAULT = True
#: ``sun_sampling_rays``'s default (see ``reports/benchmarks/summary.md``)
SUN_SAMPLING_RAYS_DEFAULT = 2
#: ``sky_at_surfaces``'s default (see ``reports/benchmarks/summary.md``)
SKY_AT_SURFACES_DEFAULT = "bsdf"


class FogPathIntegrator(FogPathCameraRay):
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
       - Path segments along which ``sun_sampling`` samples the sun's scattering from its
         integrand: 1 (the camera ray) or 2 (also the segment after the first vertex, one
         sample and shadow ray: the sun's share of double scattering; medium vertices on it
         then skip sun NEE).  Default: ``SUN_SAMPLING_RAYS_DEFAULT``.
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
     * - forced_split
       - bool
       - Forced splitting on the camera ray: every sample traces both branches at
         depth 0, the surface (or sky) weighted by the closed-form transmittance
         ``T`` and a forced medium collision on ``[0, D]`` with its light sample;
         the path then continues one branch, chosen in proportion to the branches'
         depth-0 throughputs (see :meth:`_camera_split`).  Used when the fog
         scatters, has no Local Fog Volume and ``max_depth >= 2``.  Default: ``FORCED_SPLIT_DEFAULT``.
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
        self.sun_sampling_rays = params.integer(
            props.get("sun_sampling_rays", SUN_SAMPLING_RAYS_DEFAULT),
            "sun_sampling_rays",
            source="fogpath",
            lo=1,
            hi=2,
        )
        self.forced_split = bool(props.get("forced_split", FORCED_SPLIT_DEFAULT))
        self.sky_at_surfaces = str(props.get("sky_at_surfaces", SKY_AT_SURFACES_DEFAULT))
        params.choice(self.sky_at_surfaces, "sky_at_surfaces", ("mis", "bsdf"), "fogpath")
        diameter = params.number(
            props.get("sun_angular_diameter", 0.0), "sun_angular_diameter", source="fogpath", lo=0.0, hi=10.0
        )
        #: 1 - cos of the sun disk's angular radius (float64), None for the delta sun
        self.sun_one_minus_cos = 2.0 * math.sin(math.radians(diameter) / 4.0) ** 2 if diameter > 0 else None
        self.aovs = bool(props.get("aovs", True))
        self.pixel_exact = bool(props.get("pixel_exact", False))

    # --------------------------------------------------------------- pieces
    def _transmittance(self, fog, ops, o, d, t):
        tau = fog.optical_depth(ops, o, d, t)
        return spectrum([dr.exp(-s * tau) for s in ops.params(fog.sigma_t)])

    def _draw_channel(self, sampler, active=True):
        return mi.UInt32(dr.minimum(mi.UInt32(sampler.next_1d(active) * 3.0), 2))

    def _free_flight(self, fog, ops, sampler, ray, t_surf, active):
        """Sample the next medium event before ``t_surf``.

        Returns (is_medium, t, weight): weight multiplies the throughput, i.e.
        sigma_s T / pdf at a medium vertex and T / P(pass) otherwise.  RGB
        extinction: one-sample spectral MIS *per segment*: a channel is drawn
        uniformly for this segment alone and the weight divides by the mean pdf
        over channels.  (Keeping one channel for a whole path while dividing each
        segment by its mean pdf is biased: 0.35 % too bright in the RGB furnace
        test, ``tests/test_render_bias.py``.)
        """
        if fog is None:
            return mi.Bool(False), dr.minimum(t_surf, drjit_ops().largest), mi.Spectrum(1.0)
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

    def _direct(self, scene, fog, ops, sampler, it, ctx, scatter, active, has_smooth):
        """Next-event estimation at ``it`` (a medium interaction when ``scatter`` is a
        phase function, else a surface interaction and ``scatter`` its BSDF): emitter
        sample times the closed-form fog transmittance and visibility, times the phase
        function or BSDF, MIS-weighted against it for non-delta emitters.
        Returns (contribution without the path throughput, is the sample delta).  At a surface with
        ``sky_at_surfaces = "bsdf"`` a sample of the constant sky contributes 0: the BSDF
        sample carries the sky alone (:meth:`_sky_by_bsdf`)."""
        in_medium = isinstance(scatter, mi.PhaseFunction)
        sky_by_bsdf = not in_medium and self._sky_by_bsdf(scene)
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
        if has_smooth:  # MIS only matters for emitters a sampled direction can hit
            c *= dr.select(ds.delta, 1.0, mis_weight(ds.pdf, f_pdf))
        return dr.select(visible, c * Tr, 0.0), ds.delta

    def _sky_by_bsdf(self, scene):
        """Does the BSDF sample alone carry a constant sky at surfaces (trace-time)?"""
        return self.sky_at_surfaces == "bsdf" and self._constant_sky(scene) is not None

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

    def _medium_vertex(
        self,
        scene,
        fog,
        ops,
        sampler,
        ray,
        p,
        t,
        phase,
        ctx,
        med,
        first,
        has_smooth,
        sun_ss,
        sun_sampled=None,
    ):
        """Light sample and phase sample at a medium vertex.  At the first vertex of the
        camera ray the sun is left out when it is sampled along the camera ray.
        ``sun_sampled``: lanes whose segment's sun scattering was sampled along it (default
        ``first``); their sun NEE is left out.
        Returns (contribution without the throughput, direction, phase weight, its pdf)."""
        mei = self._medium_interaction(ray, p, t)
        Ld, delta = self._direct(scene, fog, ops, sampler, mei, ctx, phase, med, has_smooth)
        if sun_ss is not None:  # the sun on this segment is sampled along it
            Ld = dr.select(delta & (first if sun_sampled is None else sun_sampled), 0.0, Ld)
        wo, w, pdf = phase.sample(ctx, mei, sampler.next_1d(med), sampler.next_2d(med), med)
        return Ld, wo, w, pdf

    # ----------------------------------------------------------------- sample
    @dr.syntax
    def sample(self, scene, sampler, ray, medium=None, active=True):
        fog, ops = self._scene_fog(scene), drjit_ops()
        has_delta, has_smooth = self._scene_lights(scene)
        phase = (
            scene.sensors()[0].get_medium().phase_function() if (fog is not None and fog.scatters) else None
        )
        phase_ctx, bsdf_ctx = mi.PhaseFunctionContext(sampler), mi.BSDFContext()

        ray, active = mi.Ray3f(ray), mi.Bool(active)
        active0 = mi.Bool(active)
        split = Split()
        β, β_cam = mi.Spectrum(1.0), mi.Spectrum(1.0)  # β_cam: the camera segment of unscattered paths
        depth, medium_first = mi.UInt32(0), mi.Bool(False)
        prev_it, prev_pdf, prev_delta = dr.zeros(mi.Interaction3f), mi.Float(1.0), mi.Bool(True)

        # ---------------- camera ray: G-buffer, T, the sun's single scattering ----------------
        si = scene.ray_intersect(ray, active)
        D0 = dr.select(si.is_valid(), si.t, ops.largest)
        gbuf = self._gbuffer(fog, ops, ray, si) if self.aovs else None
        sun_ss = self._sun_single_scatter(scene, fog, ops, sampler, ray, D0, active)

        has_lights = has_delta or has_smooth
        active &= has_lights  # no emitter: nothing to trace beyond the G-buffer
        cam = None  # with forced splitting: (surface_coverage, depth-0 surface light, q)
        forced = self.forced_split and phase is not None and fog.volume is None  # a volume: free flight
        if dr.hint(forced and has_lights and self.max_depth >= 2, mode="scalar"):
            split, β_cam, cam, ray, si, β, medium_first, prev_it, prev_pdf, prev_delta, active = (
                self._camera_split(
                    scene,
                    fog,
                    ops,
                    sampler,
                    ray,
                    si,
                    D0,
                    phase,
                    phase_ctx,
                    bsdf_ctx,
                    has_smooth,
                    sun_ss,
                    active,
                )
            )
            depth = mi.UInt32(1)
        # the sun along the depth-1 segment (its vertices scatter only when max_depth >= 3)
        ss_next = sun_ss is not None and self.sun_sampling_rays >= 2 and self.max_depth >= 3
        while dr.hint(active, max_iterations=-1, label="fogpath"):
            if dr.hint(ss_next, mode="scalar"):
                on = active & (depth == 1)
                D1 = dr.select(si.is_valid(), si.t, ops.largest)
                ss1 = self._sun_single_scatter(scene, fog, ops, sampler, ray, D1, on, samples=1)
                split = split.add(dr.select(on, β * ss1, 0.0), medium_first, mi.Bool(False))
            # ---------------- free flight to a medium vertex or the surface ----------------
            is_medium, t_end, w_ff = self._free_flight(
                fog, ops, sampler, ray, dr.select(si.is_valid(), si.t, dr.inf), active
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
            if dr.hint(phase is not None and has_lights, mode="scalar"):
                Ld, wo_m, w_m, pdf_m = self._medium_vertex(
                    scene,
                    fog,
                    ops,
                    sampler,
                    ray,
                    p_med,
                    t_end,
                    phase,
                    phase_ctx,
                    med,
                    depth == 0,
                    has_smooth,
                    sun_ss,
                    (depth <= 1) if ss_next else (depth == 0),
                )
                split = split.add(β * Ld, medium_first, depth == 0)
                wo[med], pdf_next[med], w_next[med] = wo_m, pdf_m, w_m

            # ---------------- surface vertex: light sample, BSDF sample ----------------
            surf = active & is_surface
            bsdf = si.bsdf(ray)
            if dr.hint(has_lights, mode="scalar"):
                smooth = surf & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                Ls, _ = self._direct(scene, fog, ops, sampler, si, bsdf_ctx, bsdf, smooth, has_smooth)
                split = split.add(β * Ls, medium_first, mi.Bool(False))
            bs, w_b = bsdf.sample(bsdf_ctx, si, sampler.next_1d(surf), sampler.next_2d(surf), surf)
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

        if dr.hint(sun_ss is not None, mode="scalar"):  # the camera ray's sampled sun scattering
            split = Split(split.surface, split.single + dr.select(active0, sun_ss, 0.0), split.multiple)
        return self._outputs(split, β_cam, medium_first, cam, gbuf)

    # ------------------------------------------------------------- G-buffer
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


def register() -> None:
    mi.register_integrator("fogpath", lambda props: FogPathIntegrator(props))


__all__ = ["AOV_NAMES", "FogPathIntegrator", "register"]

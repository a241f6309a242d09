"""``fogpath``: a path tracer for exact height fog, in Python with Dr.Jit loops.

.. pluginparameters::

 * - max_depth
   - int
   - Longest path (1 = single scattering and direct surface light only; -1 = no
     limit). Default: 64.
 * - rr_depth
   - int
   - Depth where Russian roulette starts. Default: 5.
 * - hide_emitters
   - bool
   - Camera rays that escape see black instead of the sky. Default: false.
 * - aovs
   - bool
   - Write the AOVs below (needed by ``fogref render``). Off, the integrator
     returns radiance only and skips the G-buffer and the split. Default: true.
 * - sun_sampling
   - bool
   - Estimate the sun's single scattering along camera rays by sampling the
     exact single-scattering integrand (zero variance without shadows); the
     first medium vertex then skips sun NEE. Used when the fog is one unbounded
     exponential layer (see ``sun_sampling_layers``) and the sun is above the
     horizon. Default: true.
 * - sun_sampling_layers
   - int
   - Most layers for which ``sun_sampling`` is used (several layers need a
     Newton inversion, which did not pay off in the benchmark). Default: 1.

What it does:

* **analytic free flight** in the fog attached to the sensor (``heightfog``):
  each exponential layer's collision distance is inverted in closed form and the
  nearest wins; RGB extinction uses one-sample spectral MIS (a channel is chosen
  per path, weights use the mean pdf over channels).  No majorant, no null
  collisions;
* **closed-form transmittance** on shadow rays, times geometric visibility
  (``ray_test``), to infinity for the sun and the sky;
* **next-event estimation** with MIS (power heuristic) for the sun
  (``directional``, delta: NEE only), the sky (``constant``/``envmap``) and area
  lights; Henyey–Greenstein phase (Mitsuba's ``hg``); any Mitsuba BSDF on surfaces;
* ``max_depth`` and Russian roulette; a camera anywhere (inside or above the fog).

It writes AOVs that split the estimate so that exactly
``L = Tsurface + single + multiple`` per sample (see ``fogref.render.render``):
``T.*`` (closed-form camera-ray transmittance, noise-free), ``Tsurface.*``
(paths whose first vertex is the first surface or the sky), ``single.*`` (direct
light at the first medium vertex), ``multiple.*`` (the rest), and the G-buffer
``distance``, ``P.*``, ``view.*``, ``hit``.

Only what the scene uses is traced: these are Python-level (trace-time)
decisions: no sun/sky -> no emitter sampling code; one layer -> one inversion;
albedo 0 -> no medium vertices (transmittance only); vacuum -> plain path tracing.

Not supported: media attached to shapes (interfaces); the fog fills all space
outside surfaces.  Differentiation.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from fogref.media import drjit_ops
from fogref.media.single_scatter import sample_sun_single_scatter, sun_sampling_applies

AOV_NAMES = (
    ["T.R", "T.G", "T.B"]
    + [f"{g}.{c}" for g in ("Tsurface", "single", "multiple") for c in "RGB"]
    + ["distance", "P.X", "P.Y", "P.Z", "view.X", "view.Y", "view.Z", "hit"]
)


class _Opaque:
    """Hides a Python object (e.g. a dataclass) from Dr.Jit's loop-state traversal."""

    __slots__ = ("_obj",)

    def __init__(self, obj):
        object.__setattr__(self, "_obj", obj)

    def __getattr__(self, name):
        return getattr(self._obj, name)


def mis_weight(pdf_a, pdf_b):
    """Power heuristic (beta = 2); 0 where undefined."""
    a2, b2 = dr.square(pdf_a), dr.square(pdf_b)
    w = a2 / (a2 + b2)
    return dr.select(dr.isfinite(w), w, 0.0)


def _spectrum(values):
    return mi.Spectrum(*values) if len(values) == 3 else mi.Spectrum(values[0])


class FogPathIntegrator(mi.SamplingIntegrator):
    """Path tracer with analytic free flight in fogref's exact fog (see module)."""

    def __init__(self, props):
        super().__init__(props)
        md = props.get("max_depth", 64)
        self.max_depth = 2**31 - 1 if md < 0 else int(md)
        self.rr_depth = int(props.get("rr_depth", 5))
        self.hide_emitters = bool(props.get("hide_emitters", False))
        self.sun_sampling = bool(props.get("sun_sampling", True))
        self.sun_sampling_layers = int(props.get("sun_sampling_layers", 1))
        self.aovs = bool(props.get("aovs", True))

    def aov_names(self):
        return list(AOV_NAMES) if self.aovs else []

    # ---------------------------------------------------------------- helpers
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
        has_delta = has_smooth = False
        for e in scene.emitters():
            if mi.has_flag(e.flags(), mi.EmitterFlags.Delta):
                has_delta = True
            else:
                has_smooth = True
        return has_delta, has_smooth

    @staticmethod
    def _scene_sun(scene):
        """(emitter, direction toward the sun, RGB irradiance) of the only delta
        directional emitter, or None (trace-time, Python floats)."""
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
        weight = float(p["sampling_weight"]) if "sampling_weight" in p else 1.0
        return delta[0], [x / n for x in w], E, weight

    def _transmittance(self, fog, ops, o, d, t):
        tau = fog.optical_depth(ops, o, d, t)
        return _spectrum([dr.exp(-s * tau) for s in fog.sigma_t])

    def _free_flight(self, fog, ops, sampler, ray, t_surf, channel, active):
        """Sample the next medium event before ``t_surf``.

        Returns (is_medium, t, weight): weight multiplies the throughput, i.e.
        sigma_s T / pdf at a medium vertex and T / P(pass) otherwise.
        """
        if not fog.scatters:  # absorption only: deterministic, exact
            t_end = dr.minimum(t_surf, ops.largest)
            return mi.Bool(False), t_end, self._transmittance(fog, ops, ray.o, ray.d, t_end)
        sig = mi.Float(fog.sigma_t[0])
        if fog.sigma_t[1] != fog.sigma_t[0] or fog.sigma_t[2] != fog.sigma_t[0]:
            sig = dr.select(channel == 1, fog.sigma_t[1], dr.select(channel == 2, fog.sigma_t[2], sig))
        variates = [-dr.log(1.0 - sampler.next_1d(active)) for _ in fog.layers]
        t_med = fog.sample_distance(ops, ray.o, ray.d, variates, sig)
        is_medium = active & (t_med < t_surf) & (t_med < ops.largest)
        t_end = dr.select(is_medium, t_med, dr.minimum(t_surf, ops.largest))
        Tr = self._transmittance(fog, ops, ray.o, ray.d, t_end)
        rho = fog.density(ops, ray.o + ray.d * dr.select(is_medium, t_med, 0.0))
        sigma_t = _spectrum([s * rho for s in fog.sigma_t])
        st = sigma_t * Tr
        pdf = dr.select(is_medium, (st[0] + st[1] + st[2]) / 3.0, (Tr[0] + Tr[1] + Tr[2]) / 3.0)
        num = dr.select(is_medium, sigma_t * _spectrum(fog.albedo) * Tr, Tr)
        w = dr.select(pdf > 0, num / pdf, 0.0)
        return is_medium, t_end, w

    def _shadow_T(self, fog, ops, p, ds, is_infinite):
        """Closed-form fog transmittance from p toward an emitter sample."""
        if fog is None:
            return mi.Spectrum(1.0)
        dist = dr.select(is_infinite, ops.largest, ds.dist)
        return self._transmittance(fog, ops, p, ds.d, dist)

    # ----------------------------------------------------------------- sample
    @dr.syntax
    def sample(self, scene, sampler, ray, medium=None, active=True):
        fog = self._scene_fog(scene)
        ops = drjit_ops()
        has_delta, has_smooth = self._scene_lights(scene)
        has_lights = has_delta or has_smooth
        phase = None
        if dr.hint(fog is not None and fog.scatters, mode="scalar"):
            phase = scene.sensors()[0].get_medium().phase_function()
        phase_ctx = mi.PhaseFunctionContext(sampler)
        bsdf_ctx = mi.BSDFContext()

        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        L = mi.Spectrum(0.0)
        L_single = mi.Spectrum(0.0)
        L_multi = mi.Spectrum(0.0)
        β = mi.Spectrum(1.0)
        depth = mi.UInt32(0)
        medium_first = mi.Bool(False)
        prev_it = dr.zeros(mi.Interaction3f)
        prev_pdf = mi.Float(1.0)
        prev_delta = mi.Bool(True)
        channel = mi.UInt32(dr.minimum(mi.UInt32(sampler.next_1d() * 3.0), 2))

        # G-buffer and noise-free camera transmittance
        si0 = scene.ray_intersect(ray, active)
        hit0 = si0.is_valid()
        T_cam = mi.Spectrum(1.0)
        track = self.aovs  # trace-time: split L into parts and write the G-buffer
        if dr.hint(track and fog is not None, mode="scalar"):
            T_cam = self._transmittance(fog, ops, ray.o, ray.d, dr.select(hit0, si0.t, ops.largest))
        L_sun_ss = mi.Spectrum(0.0)
        sun = self._scene_sun(scene) if (fog is not None and self.sun_sampling) else None
        use_sun_ss = sun is not None and sun_sampling_applies(fog._obj, sun[1], self.sun_sampling_layers) and self.max_depth >= 2
        if dr.hint(use_sun_ss, mode="scalar"):
            _, w_sun, E_sun, _ = sun
            D0 = dr.select(hit0, si0.t, ops.largest)
            t_ss, w_ss = sample_sun_single_scatter(ops, fog._obj, ray.o, ray.d, D0, w_sun, E_sun,
                                                   sampler.next_1d(active), channel)
            p_ss = ray.o + ray.d * t_ss
            vis_ss = active & ~scene.ray_test(mi.Ray3f(p_ss, mi.Vector3f(*w_sun)), active)
            L_sun_ss = dr.select(vis_ss, mi.Spectrum(*w_ss), 0.0)
        aov_g = []
        if dr.hint(track, mode="scalar"):
            aov_g = [dr.select(hit0, si0.t, 0.0)] + [dr.select(hit0, si0.p[i], 0.0) for i in range(3)] \
                + [ray.d[i] for i in range(3)] + [dr.select(hit0, 1.0, 0.0)]

        active &= has_lights  # no emitter: nothing to trace beyond the G-buffer
        si = si0  # the camera ray's intersection is reused by the first bounce
        while dr.hint(active, max_iterations=-1, label="fogpath"):
            t_surf = dr.select(si.is_valid(), si.t, dr.inf)

            # ---------------- free flight through the fog ----------------
            is_medium = mi.Bool(False)
            t_end = mi.Float(0.0)
            if dr.hint(fog is not None, mode="scalar"):
                is_medium, t_end, w_ff = self._free_flight(fog, ops, sampler, ray, t_surf, channel, active)
                β[active] *= w_ff
            medium_first |= active & (depth == 0) & is_medium
            is_surface = active & ~is_medium & si.is_valid()
            escaped = active & ~is_medium & ~si.is_valid()
            bucket_single = medium_first & (depth == 1)

            # ---------------- emission reached by the last sample ----------------
            # (only non-delta emitters can be hit: skipped for a sun-only scene)
            if dr.hint(has_smooth, mode="scalar"):
                em_active = (is_surface | escaped)
                if dr.hint(self.hide_emitters, mode="scalar"):
                    em_active &= ~((depth == 0) & escaped)
                ds = mi.DirectionSample3f(scene, si=si, ref=prev_it)
                em_pdf = scene.pdf_emitter_direction(prev_it, ds, em_active & ~prev_delta)
                Le = β * mis_weight(prev_pdf, dr.select(prev_delta, 0.0, em_pdf)) * ds.emitter.eval(si, em_active)
                Le = dr.select(em_active, Le, 0.0)
                L += Le
                if dr.hint(track, mode="scalar"):
                    L_single += dr.select(bucket_single, Le, 0.0)
                    L_multi += dr.select(medium_first & ~bucket_single, Le, 0.0)

            # NEE and a new direction only where a longer path is allowed
            # (Mitsuba's convention: max_depth = 2 is single scattering)
            active &= ~escaped & (depth + 1 < self.max_depth)

            # ---------------- medium vertex ----------------
            p_med = ray.o + ray.d * dr.select(is_medium, t_end, 0.0)
            med_active = active & is_medium
            mei = dr.zeros(mi.MediumInteraction3f)
            mei.p = p_med
            mei.t = t_end
            mei.wi = -ray.d
            mei.sh_frame = mi.Frame3f(mei.wi)
            mei.time = ray.time
            mei.wavelengths = ray.wavelengths

            wo_next = mi.Vector3f(ray.d)
            pdf_next = mi.Float(1.0)
            delta_next = mi.Bool(False)
            w_next = mi.Spectrum(1.0)
            new_origin = mi.Point3f(p_med)

            if dr.hint(phase is not None, mode="scalar"):
                if dr.hint(has_lights, mode="scalar"):
                    it_m = dr.zeros(mi.Interaction3f)
                    it_m.p = p_med
                    it_m.time = ray.time
                    it_m.wavelengths = ray.wavelengths
                    ds_m, em_w = scene.sample_emitter_direction(it_m, sampler.next_2d(med_active), False, med_active)
                    inf_m = mi.has_flag(ds_m.emitter.flags(), mi.EmitterFlags.Infinite)
                    sray = mi.Ray3f(p_med, ds_m.d)
                    sray.maxt = dr.select(inf_m, dr.inf, ds_m.dist * (1.0 - 1e-4))
                    vis = med_active & (ds_m.pdf != 0) & ~scene.ray_test(sray, med_active)
                    ph_val, ph_pdf = phase.eval_pdf(phase_ctx, mei, ds_m.d, med_active)
                    Ld = β * em_w * self._shadow_T(fog, ops, p_med, ds_m, inf_m) * ph_val
                    if dr.hint(has_smooth, mode="scalar"):  # MIS only matters for hittable emitters
                        Ld *= dr.select(ds_m.delta, 1.0, mis_weight(ds_m.pdf, ph_pdf))
                    Ld = dr.select(vis, Ld, 0.0)
                    if dr.hint(use_sun_ss, mode="scalar"):  # the sun's share at depth 0 is estimated above
                        Ld = dr.select(ds_m.delta & (depth == 0), 0.0, Ld)
                    L += Ld
                    if dr.hint(track, mode="scalar"):
                        L_single += dr.select(depth == 0, Ld, 0.0)
                        L_multi += dr.select(depth > 0, Ld, 0.0)
                wo_m, ph_w, ph_pdf_s = phase.sample(phase_ctx, mei, sampler.next_1d(med_active),
                                                    sampler.next_2d(med_active), med_active)
                wo_next[med_active] = wo_m
                pdf_next[med_active] = ph_pdf_s
                delta_next[med_active] = False
                w_next[med_active] = ph_w
            # ---------------- surface vertex ----------------
            surf_active = active & is_surface
            bsdf = si.bsdf(ray)
            if dr.hint(has_lights, mode="scalar"):
                em_ok = surf_active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                ds_s, em_ws = scene.sample_emitter_direction(si, sampler.next_2d(em_ok), False, em_ok)
                inf_s = mi.has_flag(ds_s.emitter.flags(), mi.EmitterFlags.Infinite)
                sray_s = si.spawn_ray(ds_s.d)
                sray_s.maxt = dr.select(inf_s, dr.inf, ds_s.dist * (1.0 - 1e-4))
                vis_s = em_ok & (ds_s.pdf != 0) & ~scene.ray_test(sray_s, em_ok)
                wo_l = si.to_local(ds_s.d)
                b_val, b_pdf = bsdf.eval_pdf(bsdf_ctx, si, wo_l, em_ok)
                Ls = β * em_ws * self._shadow_T(fog, ops, si.p, ds_s, inf_s) * b_val
                if dr.hint(has_smooth, mode="scalar"):
                    Ls *= dr.select(ds_s.delta, 1.0, mis_weight(ds_s.pdf, b_pdf))
                Ls = dr.select(vis_s, Ls, 0.0)
                L += Ls
                if dr.hint(track, mode="scalar"):
                    L_multi += dr.select(medium_first, Ls, 0.0)
            bs, b_w = bsdf.sample(bsdf_ctx, si, sampler.next_1d(surf_active), sampler.next_2d(surf_active),
                                  surf_active)
            wo_next[surf_active] = si.to_world(bs.wo)
            pdf_next[surf_active] = bs.pdf
            delta_next[surf_active] = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            w_next[surf_active] = b_w
            new_origin[surf_active] = si.p

            # ---------------- continue the path ----------------
            prev_it = dr.zeros(mi.Interaction3f)
            prev_it.p = dr.select(surf_active, si.p, p_med)
            prev_it.n = dr.select(surf_active, si.n, 0.0)
            prev_it.t = dr.select(surf_active, si.t, 0.0)
            prev_it.time = ray.time
            prev_it.wavelengths = ray.wavelengths
            prev_pdf = pdf_next
            prev_delta = delta_next
            β *= w_next
            ray_s = si.spawn_ray(wo_next)
            ray = dr.select(surf_active, ray_s, mi.Ray3f(new_origin, wo_next, ray.time, ray.wavelengths))
            depth[active] += 1

            β_max = dr.max(β)
            active &= β_max > 0
            rr = active & (depth >= self.rr_depth)
            q = dr.minimum(β_max, 0.95)
            β[rr] *= dr.rcp(q)
            active &= ~rr | (sampler.next_1d(rr) < q)
            si = scene.ray_intersect(ray, active)

        L += L_sun_ss
        L_single += L_sun_ss
        aovs = []
        if dr.hint(track, mode="scalar"):
            L_tsurf = L - L_single - L_multi
            aovs = [T_cam[0], T_cam[1], T_cam[2]]
            for part in (L_tsurf, L_single, L_multi):
                aovs += [part[0], part[1], part[2]]
            aovs += aov_g
        return L, mi.Bool(True), aovs

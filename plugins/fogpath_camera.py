"""Variance reduction on fogpath's camera ray (depth 0), each switched by a plugin parameter.

* the sun's single scattering along the camera ray, sampled from its exact integrand
  or a closed-form mixture (``sun_sampling``; :attr:`FogPathCameraRay.sun_sampling_layers`,
  :attr:`~FogPathCameraRay.sun_sampling_mixture`, :attr:`~FogPathCameraRay.sun_samples`;
  :func:`fogref.media.single_scatter.sun_sampling_mode`);
* forced splitting: both branches of the camera ray, the surface and a forced medium
  collision, in every sample (``forced_split``).

:class:`FogPathCameraRay` sits between the plumbing (:class:`fogref_plugins.fogpath_common.FogPathBase`)
and the estimator (:class:`fogref_plugins.fogpath.FogPathIntegrator`), whose pieces it calls:
``_transmittance``, ``_draw_channel``, ``_direct`` and ``_medium_vertex``.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi

from fogref.media import closed_form as cf
from fogref.media.single_scatter import (
    sample_sun_single_scatter,
    sample_sun_single_scatter_mixture,
    sun_sampling_mode,
)

from .fogpath_common import FogPathBase, Split, spectrum


class FogPathCameraRay(FogPathBase):
    """The camera-ray estimators of fogpath (see module)."""

    #: Most layers for which the sun's exact sampler is used (more layers: the mixture).
    #: One: for several layers its Newton inversion costs more time than the variance it
    #: removes (``reports/benchmarks/variance_reduction.md``).
    sun_sampling_layers: int = 1
    #: Where the exact sampler does not apply (fog in a box, more layers), sample the sun's
    #: single scattering from a closed-form mixture of per-layer integrands, weighted exactly.
    sun_sampling_mixture: bool = True
    #: Stratified sun samples per camera ray (each one shadow ray).
    sun_samples: int = 2

    def _sun_single_scatter(self, scene, fog, ops, sampler, ray, D, active, samples=None):
        """The sun's single scattering along the ray (the camera ray, or with
        ``sun_sampling_rays = 2`` the next segment), sampled from its exact
        integrand (``exact``) or a closed-form mixture proposal with the exact
        weight (``mixture``: bounded fog, several layers), ``sun_samples``
        stratified samples averaged (``samples``, if given, instead; None when it does not
        apply; then NEE covers it)."""
        sun = self._scene_sun(scene) if (fog is not None and self.sun_sampling) else None
        mode = (
            None
            if (sun is None or self.max_depth < 2)
            else sun_sampling_mode(fog._obj, sun[0], self.sun_sampling_layers, self.sun_sampling_mixture)
        )
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
        K, total = samples or self.sun_samples, mi.Spectrum(0.0)
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

    def _forced_collision(self, fog, ops, sampler, ray, D, active):
        """A medium collision on the camera ray's ``[0, D]`` forced to happen.

        Layer ``i`` is chosen with probability ``(1 - T_i) / sum_j (1 - T_j)``
        (``T_i``: its transmittance over ``[0, D]`` in the sampled channel) and
        inverted in closed form conditioned on a collision before ``D``; the pdf is
        the mixture ``sigma sum_i rho_i T_i(t) / sum_j (1 - T_j(D))`` (one layer:
        ``sigma_t T / (1 - T)``), averaged over the channels (one-sample spectral
        MIS for this segment).  Returns (t, weight ``sigma_s T(t) / pdf``, valid).
        Height layers only (fogpath uses free flight instead with a Local Fog Volume).
        """
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

    def _camera_split(
        self,
        scene,
        fog,
        ops,
        sampler,
        ray,
        si,
        D,
        phase,
        phase_ctx,
        bsdf_ctx,
        has_smooth,
        sun_ss,
        active,
    ):
        """Depth 0 with ``forced_split``: the surface branch (light found by the camera
        ray, light sample at the surface; weight ``T`` applied at the end) and a forced
        medium vertex (its light sample feeds ``single``), then one branch continues,
        chosen with probability ``q = T / (T + w_medium w_phase)`` (means over RGB).
        Returns (split, β_cam, (coverage, the surface branch's depth-0 light, q), ray, si,
        β, medium_first, prev_it, prev_pdf, prev_delta, active) for the path loop from
        depth 1.  ``surface_coverage`` is 1 on samples that continued the surface branch
        (for the sky: drew it with the same q) and ``surface`` their unweighted light, so that
        ``surface`` stays a ratio estimator bounded by the radiance it estimates."""
        hit, split = si.is_valid(), Split()
        T = self._transmittance(fog, ops, ray.o, ray.d, D)
        if has_smooth:
            em = active & (hit if self.hide_emitters else mi.Bool(True))
            ds = mi.DirectionSample3f(scene, si=si, ref=dr.zeros(mi.Interaction3f))
            split = split.add(dr.select(em, ds.emitter.eval(si, em), 0.0), mi.Bool(False), mi.Bool(False))
        disk = None if self.hide_emitters else self._sun_disk_seen(scene, ops, ray, active & ~hit)
        if disk is not None:  # the sun disk the camera ray sees
            split = split.add(disk, mi.Bool(False), mi.Bool(False))
        surf, bsdf = active & hit, si.bsdf(ray)
        smooth = surf & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        Ls, _ = self._direct(scene, fog, ops, sampler, si, bsdf_ctx, bsdf, smooth, has_smooth)
        split = split.add(Ls, mi.Bool(False), mi.Bool(False))
        direct = mi.Spectrum(split.surface)
        bs, w_b = bsdf.sample(bsdf_ctx, si, sampler.next_1d(surf), sampler.next_2d(surf), surf)
        t_m, w_m, med = self._forced_collision(fog, ops, sampler, ray, D, active)
        p_med = ray.o + ray.d * t_m
        Ld, wo_m, w_ph, pdf_m = self._medium_vertex(
            scene,
            fog,
            ops,
            sampler,
            ray,
            p_med,
            t_m,
            phase,
            phase_ctx,
            med,
            mi.Bool(True),
            has_smooth,
            sun_ss,
        )
        split = split.add(dr.select(med, w_m * Ld, 0.0), mi.Bool(True), mi.Bool(True))
        # q = T / (T + w_medium) >= T: it must not depend on the surface branch's own samples
        # (the ratio estimator `surface` keeps the samples that continued it), and q >= T
        # keeps `surface` defined wherever the old scatter-or-reach choice defined it.
        # A ray to the sky has no surface to continue: it always continues the medium and
        # its q only draws surface_coverage, so that `surface` is undefined where T ~ 0.
        ms = dr.mean(T)
        mm = dr.select(med, dr.mean(w_m * w_ph), 0.0)
        q = dr.select(ms + mm > 0, ms / (ms + mm), 0.0)  # probability of continuing the surface branch
        chose_s = sampler.next_1d(active) < q
        go_s = surf & chose_s
        go_m = med & dr.select(hit, ~chose_s & (q < 1), True)
        β = dr.select(go_s, w_b / q, dr.select(go_m, w_m * w_ph / dr.select(hit, 1.0 - q, 1.0), 0.0))
        prev_it = self._vertex(ray, si, go_s, p_med)
        prev_pdf = dr.select(go_s, bs.pdf, pdf_m)
        prev_delta = go_s & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        ray = dr.select(
            go_s, si.spawn_ray(si.to_world(bs.wo)), mi.Ray3f(p_med, wo_m, ray.time, ray.wavelengths)
        )
        active = (go_s | go_m) & (dr.max(β) > 0) & (self.max_depth > 1)
        si = scene.ray_intersect(ray, active)
        cam = (chose_s, direct, dr.select(hit, q, 1.0))  # surface_coverage, the sample of `surface`
        return split, T, cam, ray, si, β, go_m, prev_it, prev_pdf, prev_delta, active

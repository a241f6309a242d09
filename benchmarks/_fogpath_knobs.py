"""``fogpath_knobs``: fogpath with its sun samplers' and other variance reduction's settings as
plugin parameters, for the benchmarks that measure them (fogpath itself fixes them:
:meth:`fogref_plugins.fogpath.FogPathIntegrator._sun_sampler`).

* ``sun_sampling_layers`` (int in [1, 16], default 1): most layers for which the sun's exact
  sampler is used (more layers: the mixture);
* ``sun_sampling_mixture`` (bool, default true): the closed-form mixture where the exact
  sampler does not apply;
* ``sun_samples`` (int in [1, 64], default ``SUN_SAMPLES``, 4): stratified sun samples per
  camera ray;
* ``sun_guiding`` (float in [0, 0.95], default 0: fogpath's phase sampling): the share of a
  Henyey-Greenstein lobe around the direction toward the sun in the phase sample at medium
  vertices (:class:`SunGuidedPhase`);
* ``sun_guiding_g`` (float in [0, 0.99], default: the fog's ``g``, at least 0.5): that lobe's
  asymmetry;
* ``ms_split`` (int in [1, 16], default 1: fogpath's one continuation): continuation splitting
  on the camera ray (:meth:`FogPathKnobs._split_sample`): the camera ray's depth-0 stage (hit,
  G-buffer, the sun's sampled single scattering, the surface's light) is traced once, and what
  follows it (fogpath's forced collision with its light sample, the choice between the surface
  and the medium branch, and the path from depth 1) ``N`` times, each weighted ``1 / N`` (the
  forced collisions' light samples always; the paths as ``ms_split_by`` says);
* ``ms_split_by`` (``"fixed"``, default, ``"branch"``, ``"single"`` or ``"stddev"``):
  ``N = ms_split`` on every camera ray, each continuation fogpath's (a branch drawn with
  ``q``); ``"branch"``, ``N = ms_split >= 2`` and no branch drawn: on a ray that hits a surface
  the first continues the surface branch (weight 1) and the other ``N - 1`` the medium branch
  (weight ``1 / (N - 1)`` each), on a ray to the sky all ``N`` the medium branch; or ``N - 1``
  in proportion to an estimate ``x`` of the continuation's
  expected contribution, ``ms_split`` on average over the pass, ``N`` in [1, ``ms_split_max``]
  (:meth:`FogPathKnobs._split_weights`): ``"single"``, ``x`` the camera ray's sampled single
  scattering of the sun; ``"stddev"``, ``x`` an estimate of the continuation's standard
  deviation (Neyman allocation) from it and the branch probability;
* ``ms_split_max`` (int in [1, 64], default ``4 ms_split``, at most 16): the most
  continuations of one camera ray with ``ms_split_by`` ``"single"`` or ``"stddev"``;
* ``sky_along_segments`` (bool, default true: fogpath's way): false adds the residual's closed form
  and samples its residual at every medium vertex, as fogpath did before
  :meth:`~fogref_plugins.fogpath.FogPathIntegrator._sky_on_segment`;
* ``surface_control`` (bool, default true): false leaves out the control variate ``B`` at the
  surfaces that segments after the camera ray end on.  Both also read ``"true"`` and ``"false"``
  (``cycles_peer.py --fogpath KEY=VALUE``).

The knobs hold no copy of fogpath's tracing: they override fogpath's ``_sun_sampler`` and
``_medium_vertex`` (the phase sample), and continuation splitting runs fogpath's own camera
stage (``_camera_hit``, ``_camera_light``), forced-splitting continuation (``_continuation``)
and path loop (``_trace``) on a wavefront of its own, so what the benchmarks measure is today's
fogpath.  Importing this module registers the plugin (after ``_common`` set the variant).
"""

from __future__ import annotations

import math

from _common import dr, mi
from fogref_plugins.fogpath import SUN_SAMPLES, FogPathIntegrator, Split

from fogref import params
from fogref.errors import ParameterError
from fogref.media.single_scatter import sun_sampling_mode

SOURCE = "fogpath_knobs"


def hg_lobe_pdf(g: float, cos):
    """Henyey-Greenstein density [1/sr] of a direction at cosine ``cos`` (in [-1, 1]) from
    the lobe's axis, asymmetry ``g`` in [0, 1): ``(1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^1.5)``
    (Henyey & Greenstein, ApJ 93, 1941), in [(1 - g) / (4 pi (1 + g)^2), (1 + g) / (4 pi (1 - g)^2)]."""
    return (1.0 - g * g) / (4.0 * math.pi) * dr.power(1.0 + g * g - 2.0 * g * cos, -1.5)


def hg_lobe_sample(g: float, axis, u):
    """A direction drawn from the Henyey-Greenstein lobe of asymmetry ``g`` in [0, 1) around the
    unit vector ``axis``, from ``u`` in [0, 1)^2 (the inverse CDF of the cosine, Pharr, Jakob &
    Humphreys, *Physically Based Rendering* 3rd ed., section 15.2.3; uniform on the sphere for
    ``g`` below 1e-3)."""
    if g < 1e-3:
        cos = 1.0 - 2.0 * u.x
    else:
        sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x)
        cos = dr.clip((1.0 + g * g - sq * sq) / (2.0 * g), -1.0, 1.0)
    sin = dr.safe_sqrt(1.0 - cos * cos)
    s, c = dr.sincos(2.0 * dr.pi * u.y)
    return mi.Frame3f(axis).to_world(mi.Vector3f(c * sin, s * sin, cos))


class SunGuidedPhase(mi.PhaseFunction):
    """The fog's phase function ``phase``, sampled from the one-sample mixture ``(1 - share)
    p_phase + share p_lobe``, ``p_lobe`` the Henyey-Greenstein lobe of asymmetry ``g`` around
    ``to_sun``.  ``sample`` returns the direction, ``f / p_mix`` and ``p_mix``; ``eval_pdf``
    returns ``(f, p_mix)``, so that next-event estimation's MIS weight uses the density the
    phase sample was drawn with (the balance heuristic of the mixture's two techniques inside,
    the power heuristic against light sampling outside; Veach 1997, ch. 9).  Unbiased for any
    ``share`` in [0, 1): ``p_mix > 0`` wherever ``f > 0``."""

    def __init__(self, phase, to_sun, g: float, share: float):
        super().__init__(mi.Properties())
        self.phase, self.to_sun, self.g, self.share = phase, to_sun, g, share

    def _pdf(self, ctx, mei, wo, active):
        f, p = self.phase.eval_pdf(ctx, mei, wo, active)
        lobe = hg_lobe_pdf(self.g, dr.dot(wo, self.to_sun))
        return f, (1.0 - self.share) * p + self.share * lobe

    def sample(self, ctx, mei, sample1, sample2, active=True):
        lobe = sample1 < self.share
        s1 = dr.select(lobe, sample1 / self.share, (sample1 - self.share) / (1.0 - self.share))
        wo_phase, _, _ = self.phase.sample(ctx, mei, s1, sample2, active)
        wo = dr.select(lobe, hg_lobe_sample(self.g, self.to_sun, sample2), wo_phase)
        f, pdf = self._pdf(ctx, mei, wo, active)
        return wo, dr.select(pdf > 0, f / pdf, 0.0), pdf

    def eval_pdf(self, ctx, mei, wo, active=True):
        return self._pdf(ctx, mei, wo, active)


class WideSampler:
    """The random numbers of the split continuations: one PCG32 stream per continuation (lane),
    drawn as Mitsuba's ``independent`` sampler draws them (``next_1d``, ``next_2d``; a masked
    draw leaves the state of the lanes off the mask unchanged)."""

    DRJIT_STRUCT = {"rng": mi.PCG32}

    def __init__(self, rng=None):
        self.rng = mi.PCG32() if rng is None else rng

    def next_1d(self, active=True):
        return self.rng.next_float32(mi.Bool(active))

    def next_2d(self, active=True):
        return mi.Point2f(self.next_1d(active), self.next_1d(active))


def _flag(props, name: str, default: bool = True) -> bool:
    """The boolean parameter ``name`` (true or false; the strings ``"true"``, ``"false"`` of
    ``cycles_peer.py --fogpath KEY=VALUE`` too); anything else a ParameterError naming it."""
    value = props.get(name, default)
    value = {"true": True, "false": False}.get(value, value) if isinstance(value, str) else value
    if not isinstance(value, bool):
        raise ParameterError(SOURCE, name, f"expected true or false, got {value!r}")
    return value


class FogPathKnobs(FogPathIntegrator):
    """fogpath with ``sun_sampling_layers``, ``sun_sampling_mixture``, ``sun_samples``,
    ``sun_guiding``, ``sun_guiding_g``, the ``ms_split`` settings, ``sky_along_segments`` (false:
    the sky's closed form added at the vertices of segments after the camera ray, as fogpath did
    before :meth:`FogPathIntegrator._sky_on_segment`) and ``surface_control`` (false: no control variate
    at the surfaces those segments end on) read from the plugin's parameters (checked by fogref's
    validator: one line naming the parameter and range)."""

    def __init__(self, props):
        super().__init__(props)
        layers = props.get("sun_sampling_layers", 1)
        self.sun_sampling_layers = params.integer(layers, "sun_sampling_layers", source=SOURCE, lo=1, hi=16)
        mixture = props.get("sun_sampling_mixture", True)
        if not isinstance(mixture, bool):
            raise ParameterError(SOURCE, "sun_sampling_mixture", f"expected true or false, got {mixture!r}")
        self.sun_sampling_mixture = mixture
        self.sun_samples = params.integer(
            props.get("sun_samples", SUN_SAMPLES), "sun_samples", source=SOURCE, lo=1, hi=64
        )
        self.sun_guiding = params.number(
            props.get("sun_guiding", 0.0), "sun_guiding", source=SOURCE, lo=0.0, hi=0.95
        )
        g = props.get("sun_guiding_g", None)
        if g is not None:
            g = params.number(g, "sun_guiding_g", source=SOURCE, lo=0.0, hi=0.99)
        self.sun_guiding_g = g
        self.sky_along_segments = _flag(props, "sky_along_segments")
        self.surface_control = _flag(props, "surface_control")
        self.ms_split = params.integer(props.get("ms_split", 1), "ms_split", source=SOURCE, lo=1, hi=16)
        self.ms_split_by = str(props.get("ms_split_by", "fixed"))
        params.choice(self.ms_split_by, "ms_split_by", ("fixed", "single", "stddev", "branch"), SOURCE)
        if self.ms_split_by == "branch" and self.ms_split < 2:
            raise ParameterError(
                SOURCE, "ms_split", f"must be >= 2 with ms_split_by 'branch', got {self.ms_split}"
            )
        self.ms_split_max = params.integer(
            props.get("ms_split_max", min(4 * self.ms_split, 16)), "ms_split_max", source=SOURCE, lo=1, hi=64
        )

    def _medium_vertex(self, tr, sampler, ray, p, t, med, sun_sampled, closed=True, deferred=False):
        """fogpath's medium vertex, its phase function sampled by :class:`SunGuidedPhase` when
        ``sun_guiding`` is above 0 and the scene has a sun."""
        sun = self._scene_sun(tr.scene) if self.sun_guiding > 0 else None
        if sun is None:
            return super()._medium_vertex(tr, sampler, ray, p, t, med, sun_sampled, closed, deferred)
        g = self.sun_guiding_g if self.sun_guiding_g is not None else max(float(tr.fog.g), 0.5)
        phase = tr.phase
        tr.phase = SunGuidedPhase(phase, mi.Vector3f(*tr.ops.params(sun[0])), g, self.sun_guiding)
        try:
            return super()._medium_vertex(tr, sampler, ray, p, t, med, sun_sampled, closed, deferred)
        finally:
            tr.phase = phase

    def _sun_sampler(self, fog, w_sun):
        mode = sun_sampling_mode(fog, w_sun, self.sun_sampling_layers, self.sun_sampling_mixture)
        return mode, self.sun_samples

    # ------------------------------------------------ continuation splitting (ms_split)
    def sample(self, scene, sampler, ray, medium=None, active=True):
        """fogpath's ``sample``, or with ``ms_split`` above 1 or ``ms_split_by`` not ``fixed`` (where
        fogpath splits the camera ray, :meth:`FogPathIntegrator._splits`) the camera ray's
        continuation split (:meth:`_split_sample`)."""
        tr = self._tracing(scene, sampler)
        if (self.ms_split == 1 and self.ms_split_by == "fixed") or not self._splits(tr):
            return super().sample(scene, sampler, ray, medium, active)
        return self._split_sample(tr, sampler, mi.Ray3f(ray), mi.Bool(active))

    def _split_sample(self, tr, sampler, ray, active):
        """The camera ray's depth-0 stage once per lane (hit, G-buffer, ``T``, the sun's sampled
        single scattering, the surface branch's light: fogpath's :meth:`_camera_hit` and
        :meth:`_camera_light`), then ``N`` continuations per lane (fogpath's :meth:`_continuation`,
        its BSDF sample drawn after the medium vertex, and path loop :meth:`_trace`) on a
        wavefront of their own with a PCG32 stream each, summed back per lane with the weights
        ``ms_split_by`` gives (``1 / N`` each, or with ``"branch"`` 1 for the surface branch and
        ``1 / (N - 1)`` for the medium branch's).  ``N`` depends on the depth-0 stage only (never
        on a continuation's samples), so the weighted sum is an unbiased estimate of one
        continuation; ``"single"`` and ``"stddev"`` fall back to ``N = ms_split`` where the
        sun is not sampled along the camera ray.  Outputs by fogpath's ``_outputs``; per lane,
        ``surface_coverage`` is the weighted share of its continuations that continued the
        surface branch (``q`` on a ray to the sky with ``"branch"``) and ``surface`` their light
        without the ``1/q`` weight."""
        n = dr.width(ray.d)
        si, D0, gbuf, sun_ss = self._camera_hit(tr, sampler, ray, active)
        hit = si.is_valid()
        T = self._transmittance(tr.fog, tr.ops, ray.o, ray.d, D0)
        direct = self._camera_light(tr, sampler, ray, si, active)
        # continuations per lane, on a wavefront of n K lanes (fixed, so its kernel is reused)
        K = k_max = self.ms_split
        N = dr.full(mi.UInt32, K, n)
        if self.ms_split_by in ("single", "stddev") and sun_ss is not None:
            x = dr.select(active, self._split_weights(tr, sun_ss, T, hit), 0.0)
            total = dr.sum(x)  # over the pass's lanes; N below sums to at most n K
            extra = dr.select(total > 0, (K - 1) * (1.0 - 1e-5) * n * x / total, float(K - 1))
            k_max = max(self.ms_split_max, 1)
            N = mi.UInt32(1.0 + dr.minimum(dr.floor(extra), float(k_max - 1)))
        seed = (mi.UInt32(sampler.next_1d(active) * 65536.0) << 16) | mi.UInt32(
            sampler.next_1d(active) * 65536.0
        )
        dr.eval(si, D0, T, direct, N, seed, sun_ss, gbuf)
        start = dr.prefix_sum(N)  # lane l owns the slots [start_l, start_l + N_l)
        mark = dr.zeros(mi.UInt32, n * K)
        dr.scatter(mark, mi.UInt32(1), start, start < n * K)
        slot = dr.arange(mi.UInt32, n * K)
        owner = dr.minimum(dr.cumsum(mark), n) - 1
        total_n = int(dr.sum(N)[0])
        if total_n > n * K:  # the allocation's floors keep it at most n K; never drop a continuation
            raise RuntimeError(
                f"{SOURCE}: {total_n} continuations do not fit the {n * K} lanes of the wavefront"
            )
        live = slot < total_n
        dr.eval(owner, live)
        # each continuation's stream: its slot, and a start hashed from the lane's seed and the slot
        # (TEA, Zafar et al. 2010), so no two share a start (PCG32 streams that do are correlated)
        h0, h1 = mi.sample_tea_32(dr.gather(mi.UInt32, seed, owner), slot)
        ws = WideSampler(mi.PCG32(n * K, (mi.UInt64(h0) << 32) | mi.UInt64(h1), mi.UInt64(slot)))
        at = lambda v: dr.gather(type(v), v, owner)  # noqa: E731
        ray_w, si_w, T_w, direct_w = at(ray), at(si), at(T), at(direct)
        hit_w, N_w = si_w.is_valid(), mi.Float(at(N))
        first = slot == at(start)  # a lane's first continuation
        branch = self.ms_split_by == "branch"
        D_w = dr.select(hit_w, si_w.t, tr.ops.largest)
        slot_s = first if branch else None
        path, chose_s, q, ld = self._continuation(tr, ws, ray_w, si_w, D_w, T_w, at(active), False, slot_s)
        split = self._trace(tr, ws, path)[0]
        dr.eval(split, chose_s, q, ld)  # one wavefront kernel (each sum below would re-run the loop)
        w = dr.select(live, dr.rcp(N_w), 0.0)  # the forced collisions' light samples: their mean
        if branch:  # hit: the first continues the surface branch (weight 1), the others the medium
            w_b = dr.select(
                live, dr.select(hit_w, dr.select(first, 1.0, dr.rcp(N_w - 1.0)), dr.rcp(N_w)), 0.0
            )
            cov = dr.select(hit_w, dr.select(first & live, 1.0, 0.0), q * w)
            s_out = dr.select(hit_w, dr.select(first & live, direct_w + split.surface, 0.0), q * w * direct_w)
        else:  # each continuation fogpath's, weight 1/N
            w_b, cov = w, dr.select(chose_s, w, 0.0)
            s_out = dr.select(chose_s, direct_w + q * split.surface, 0.0) * w
        cont = [
            split.surface * w_b,
            split.single * w_b + ld * w,
            split.multiple * w_b,
            mi.Spectrum(cov),
            s_out,
        ]
        flat = [c[i] for c in cont for i in range(3)]
        dr.eval(flat)
        # per lane, the sum of its continuations' values / N, in slot order (deterministic,
        # unlike atomic scatter-adds): lane l's continuations are the slots [start_l, start_l + N_l)
        sums = [mi.Float(0.0)] * len(flat)
        for j in range(k_max):
            on = active & (j < N)
            sums = [a + dr.gather(mi.Float, f, start + j, on) for a, f in zip(sums, flat)]
        back = [mi.Spectrum(*sums[3 * i : 3 * i + 3]) for i in range(len(cont))]
        single = back[1] + (0.0 if sun_ss is None else dr.select(active, sun_ss, 0.0))
        return self._outputs(Split(direct + back[0], single, back[2]), T, gbuf, back[3][0], back[4])

    def _split_weights(self, tr, sun_ss, T, hit):
        """Per camera ray, the estimate ``x >= 0`` of the continuation's contribution that
        ``ms_split_by`` allocates continuations by (``N - 1`` in proportion to it), from the
        depth-0 stage only: ``"single"``, the mean over RGB of the sun's single scattering
        sampled along the camera ray (``s``); ``"stddev"``, the standard deviation of one
        continuation if its radiance scales as ``s / m`` (``m = albedo (1 - T)``, the forced
        collision's mean weight, means over RGB) and the medium branch, taken with probability
        ``1 - q = m / (T + m)`` on a ray that hits a surface, dominates its variance:
        ``s sqrt((T + m) / m)`` there, ``s`` on a ray to the sky (always the medium branch)."""
        s = dr.mean(sun_ss)
        if self.ms_split_by == "single":
            return s
        t = dr.mean(T)
        m = dr.maximum(dr.mean(mi.Spectrum(*tr.ops.params(tr.fog.albedo))) * (1.0 - t), 1e-6)
        return s * dr.select(hit, dr.sqrt((t + m) / m), 1.0)


mi.register_integrator("fogpath_knobs", lambda props: FogPathKnobs(props))

"""The ground-truth schema: its channel groups, declared once, and its one reader.

A ground truth is one multi-channel float32 EXR.  The integrator's per-sample outputs, the
EXR writer, ``compare``, ``study`` and the table of ``docs/schema.md`` derive from
:data:`GROUPS`; :func:`load_truth` is the one reader, :class:`Truth` what the rest of fogref
sees.  ``final = attenuated_surface + inscatter`` and ``inscatter = single + multiple`` hold per
pixel exactly; ``surface`` is a ratio estimator, 0 where ``surface_coverage == 0``; no part is
divided by ``T``.  Each Monte Carlo part carries ``stderr.<part>.*`` and ``corr.<part>.*``
(:meth:`Truth.noise_cov`); ``docs/schema.md`` says how each is estimated.

Examples
--------
>>> [g.name for g in GROUPS][:4]
['final', 'T', 'attenuated_surface', 'inscatter']
>>> channel_names("inscatter")
['inscatter.R', 'inscatter.G', 'inscatter.B']
>>> channel_names("final"), channel_names("hit")
(['R', 'G', 'B'], ['hit'])
>>> stderr_names("final")
['stderr.R', 'stderr.G', 'stderr.B']
>>> correlation_names("inscatter")
['corr.inscatter.RG', 'corr.inscatter.RB', 'corr.inscatter.GB']
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fogref.errors import FogrefError
from fogref.exrio import read_exr

#: Version of the channel layout below; stored in the header as ``fogref.schema``.
#: 3 added the ``corr.*`` channels; 2 (no correlations) is still read, see :func:`truth_from_channels`.
SCHEMA_VERSION = 3
#: Channel index pairs of the ``corr.*`` channels and of the renderer's cross moments, in order.
CHANNEL_PAIRS: tuple[tuple[int, int], ...] = ((0, 1), (0, 2), (1, 2))
RGB = ("R", "G", "B")
XYZ = ("X", "Y", "Z")


@dataclass(frozen=True)
class Group:
    """One channel group of the ground truth.

    name:       the group's name (``final`` is written as bare ``R,G,B``).
    components: ``("R","G","B")``, ``("X","Y","Z")`` or ``()`` for one scalar channel.
    meaning:    one line for the docs (units in brackets).
    noisy:      a Monte Carlo part: it has ``stderr.`` channels.
    """

    name: str
    components: tuple[str, ...]
    meaning: str
    noisy: bool = False

    @property
    def prefix(self) -> str:
        return "" if self.name == "final" else self.name + "."


#: Every group of the ground-truth EXR, in the order ``docs/schema.md`` lists them.
GROUPS: tuple[Group, ...] = (
    Group("final", RGB, "total radiance = attenuated_surface + inscatter", True),
    Group("T", RGB, "camera-ray transmittance to the first surface (or to infinity), closed form", True),
    Group(
        "attenuated_surface", RGB, "surface (or sky) radiance as it reaches the camera through the fog", True
    ),
    Group("inscatter", RGB, "radiance the medium adds = single + multiple", True),
    Group("single", RGB, "direct sun and sky light scattered once, at the first medium vertex", True),
    Group("multiple", RGB, "everything else the medium adds", True),
    Group(
        "surface", RGB, "surface (or sky) radiance before the fog; defined where surface_coverage > 0", True
    ),
    Group(
        "surface_coverage", (), "fraction of samples whose camera ray reached the surface or sky unscattered"
    ),
    Group("distance", (), "distance from the camera to the first surface [m]; 0 for sky"),
    Group("P", XYZ, "world position of the first surface [m]; 0 for sky"),
    Group("view", XYZ, "unit camera-ray direction (world, y-up)"),
    Group("hit", (), "fraction of samples whose camera ray hits a surface (0 or 1 when pixel-exact)"),
)
_BY_NAME = {g.name: g for g in GROUPS}
#: The radiance-like parts compared against models (each ``(H, W, 3)``).
PARTS: tuple[str, ...] = tuple(g.name for g in GROUPS if g.components == RGB)
#: The parts a fog model or an engine's images are compared on (``compare``'s reports and their
#: viewer), in a report's order and spelled as :class:`Truth`'s attributes (:func:`part_attribute`).
COMPARED_PARTS: tuple[str, ...] = ("final", "transmittance", "inscatter", "attenuated_surface")
#: What the integrator writes per sample (besides R,G,B), in this order:
#: the parts above with ``surface`` as the unattenuated sample (0 where it did
#: not reach the surface), then the coverage indicator and the G-buffer.
SAMPLE_GROUPS: tuple[str, ...] = tuple(
    "T attenuated_surface inscatter single multiple surface surface_coverage distance P view hit".split()
)
#: Per-sample groups whose second moments the renderer accumulates.
SQUARED_GROUPS: tuple[str, ...] = PARTS


def part_attribute(name: str) -> str:
    """The one alias of the schema: the group ``T`` is the attribute ``transmittance`` of a
    :class:`Truth` (and its key in ``stderr``/``corr``, and a report's part name); every other
    part has one name.  The inverse is :func:`part_group`.

    >>> part_attribute("T"), part_attribute("transmittance"), part_attribute("inscatter")
    ('transmittance', 'transmittance', 'inscatter')
    """
    return "transmittance" if name == "T" else name


def part_group(name: str) -> str:
    """The schema's group name of a part (``transmittance`` is ``T``), see :func:`part_attribute`.

    >>> part_group("transmittance"), part_group("T"), part_group("final")
    ('T', 'T', 'final')
    """
    return "T" if name == "transmittance" else name


def group(name: str) -> Group:
    """The :class:`Group` called ``name``; FogrefError listing the groups if unknown."""
    try:
        return _BY_NAME[name]
    except KeyError:
        raise FogrefError(f"no channel group '{name}' (groups: {', '.join(_BY_NAME)})") from None


def channel_names(name: str) -> list[str]:
    """EXR channel names of group ``name`` (``final`` -> ``R, G, B``)."""
    g = group(name)
    if not g.components:
        return [g.name]
    return [g.prefix + c for c in g.components]


def stderr_names(name: str) -> list[str]:
    """EXR channel names of the standard error of group ``name``."""
    if not group(name).noisy:
        raise FogrefError(f"channel group '{name}' is not a Monte Carlo part: it has no standard error")
    return ["stderr." + c for c in channel_names(name)]


def correlation_names(name: str) -> list[str]:
    """EXR channel names of the noise correlations between the channels of group ``name``
    (pairs :data:`CHANNEL_PAIRS`: RG, RB, GB)."""
    g = group(name)
    if not g.noisy:
        raise FogrefError(f"channel group '{name}' is not a Monte Carlo part: it has no noise correlation")
    return ["corr." + g.prefix + g.components[i] + g.components[j] for i, j in CHANNEL_PAIRS]


def sample_channel_names() -> list[str]:
    """Per-sample AOV names of the integrator (after its R,G,B), from :data:`SAMPLE_GROUPS`."""
    return [c for g in SAMPLE_GROUPS for c in channel_names(g)]


def exr_channel_names() -> list[str]:
    """Every channel of a schema-2 ground-truth EXR."""
    names = [c for g in GROUPS for c in channel_names(g.name)]
    names += [s for g in GROUPS if g.noisy for s in stderr_names(g.name)]
    return names + [s for g in GROUPS if g.noisy for s in correlation_names(g.name)]


def schema_table() -> str:
    """The channel table of ``docs/schema.md`` (Markdown), generated from :data:`GROUPS`."""
    rows = ["| channels | meaning |", "|---|---|"]
    for g in GROUPS:
        names = channel_names(g.name)
        label = ",".join(names) if len(names) == 1 or g.name == "final" else f"{g.prefix}*"
        rows.append(f"| `{label}` | {g.meaning} |")
    rows.append("| `stderr.<part>.*` | per-pixel standard error of each Monte Carlo part |")
    rows.append("| `corr.<part>.RG,RB,GB` | correlation of the noise of the part's channels, in [-1, 1] |")
    return "\n".join(rows)


class _NumpyArrays:
    """The array operations :func:`moments_to_channels` needs, for numpy arrays."""

    asarray = staticmethod(lambda x: np.asarray(x, dtype=np.float64))
    where = staticmethod(np.where)
    sqrt = staticmethod(np.sqrt)
    maximum = staticmethod(np.maximum)
    minimum = staticmethod(np.minimum)
    zeros_like = staticmethod(np.zeros_like)
    stack_last = staticmethod(lambda xs: np.stack(xs, -1))


class _DrJitArrays:
    """The same for Dr.Jit float64 tensors (the render driver's sums stay on the device)."""

    def __init__(self) -> None:
        import drjit as dr

        self.asarray = lambda x: x
        self.where, self.sqrt, self.maximum, self.minimum = dr.select, dr.sqrt, dr.maximum, dr.minimum
        self.zeros_like = lambda x: dr.zeros(type(x), x.shape)
        self.stack_last = lambda xs: dr.concat([x[..., None] for x in xs], axis=len(xs[0].shape))


def _arrays_for(x: Any) -> Any:
    return _DrJitArrays() if type(x).__module__.startswith("drjit") else _NumpyArrays


def moments_to_channels(
    sums: dict[str, Any], squares: dict[str, Any], n: int, cross: dict[str, Any]
) -> dict[str, Any]:
    """EXR channels from per-pixel sums of the per-sample outputs.

    ``sums``: group -> ``(H, W, k)`` float64 sum over a pixel's ``n >= 1`` samples, for each of
    ``("final",) + SAMPLE_GROUPS``, as numpy arrays or Dr.Jit float64 tensors (then so is the
    result).  ``squares`` and ``cross``: group -> ``(H, W, 3)`` sums of squares and of the
    pair products :data:`CHANNEL_PAIRS` (R*G, R*B, G*B), for :data:`SQUARED_GROUPS`.
    Returns channel -> ``(H, W)`` float64: means, the ratio estimator ``surface`` (0 where no
    sample reached the surface), ``stderr.*`` (0 if ``n == 1``) and ``corr.*`` in [-1, 1] (0
    where a channel has no noise, or ``n == 1``).

    Examples
    --------
    Two samples of one pixel: one reached the surface (radiance 2), one scattered.

    >>> import numpy as np
    >>> one = lambda v: np.full((1, 1, 3), float(v))
    >>> sums = {g: one(0) for g in ("final",) + SAMPLE_GROUPS}
    >>> sums["surface"], sums["surface_coverage"] = one(2), np.ones((1, 1, 1))
    >>> squares = {g: one(0) for g in SQUARED_GROUPS}
    >>> squares["surface"] = one(4)
    >>> cross = {g: one(0) for g in SQUARED_GROUPS}
    >>> c = moments_to_channels(sums, squares, 2, cross)
    >>> float(c["surface.R"][0, 0]), float(c["surface_coverage"][0, 0]), float(c["stderr.surface.R"][0, 0])
    (2.0, 0.5, 0.0)

    Two samples of grey light, (1, 1, 1) and (3, 3, 3): the channels' noise is one noise.

    >>> sums["final"], squares["final"], cross["final"] = one(4), one(10), one(10)
    >>> c = moments_to_channels(sums, squares, 2, cross)
    >>> float(c["stderr.R"][0, 0]), float(c["corr.RG"][0, 0])
    (1.0, 1.0)
    """
    xp = _arrays_for(next(iter(sums.values())))
    out = {}
    # every division by a number is a product with its reciprocal, as Dr.Jit computes ``x / n``,
    # so that numpy and Dr.Jit arrays give the same bits
    inv_n = 1.0 / n
    mean = {g: xp.asarray(s) * inv_n for g, s in sums.items()}
    for g in ("final",) + SAMPLE_GROUPS:
        if g == "surface":
            continue
        for i, c in enumerate(channel_names(g)):
            out[c] = mean[g][..., i]
    cover = mean["surface_coverage"][..., 0]
    valid = cover > 0
    safe = xp.where(valid, cover, 1.0)
    for i, c in enumerate(channel_names("surface")):
        ratio = mean["surface"][..., i] / safe
        out[c] = xp.where(valid, ratio, 0.0)
    for g in SQUARED_GROUPS:
        m2 = xp.asarray(squares[g]) * inv_n
        mx = xp.asarray(cross[g]) * inv_n
        if g == "surface":
            # the delta method for the ratio r = E[s]/E[c] (docs/schema.md, "surface")
            r = xp.stack_last([out[c] for c in channel_names("surface")])
            var = (m2 - 2 * r * mean["surface"] + r * r * cover[..., None]) / safe[..., None] ** 2

            def cov(i: int, j: int, mij: Any, r: Any = r) -> Any:
                m = mean["surface"]
                return (
                    mij - r[..., j] * m[..., i] - r[..., i] * m[..., j] + r[..., i] * r[..., j] * cover
                ) / safe**2
        else:
            var = m2 - mean[g] ** 2

            def cov(i: int, j: int, mij: Any, r: Any = mean[g]) -> Any:
                return mij - r[..., i] * r[..., j]

        var = xp.maximum(var, 0.0)
        se = xp.sqrt(var * (1.0 / max(n - 1, 1))) if n > 1 else xp.zeros_like(var)
        for i, c in enumerate(stderr_names(g)):
            out[c] = xp.where(valid, se[..., i], 0.0) if g == "surface" else se[..., i]
        for k, ((i, j), c) in enumerate(zip(CHANNEL_PAIRS, correlation_names(g))):
            vv = var[..., i] * var[..., j]
            has = (vv > 0) & valid if g == "surface" else vv > 0
            rho = cov(i, j, mx[..., k]) / xp.sqrt(xp.where(has, vv, 1.0))
            rho = xp.maximum(xp.minimum(rho, 1.0), -1.0)
            out[c] = xp.where(has, rho, 0.0) if n > 1 else xp.zeros_like(rho)
    return out


@dataclass(repr=False)
class Truth:
    """One ground truth, as every part of fogref reads it.  Arrays are float64, ``(H, W, 3)``
    for the parts (``transmittance`` is the ``T`` group), ``(H, W)`` for scalars.

    stderr, corr: part -> its per-pixel standard error (same shape) and the ``(H, W, 3)``
    correlation of its channels' noise (pairs :data:`CHANNEL_PAIRS`, in [-1, 1]).
    surface_coverage: [0, 1].  distance [m] (0 for sky), position [m], view (unit, y-up).
    hit_fraction: [0, 1], strictly inside only on an anti-aliased render's silhouettes.
    camera: ``(3,)`` [m].  sun_direction: ``(3,)`` unit toward the sun, or None.
    params: the decoded ``fogref.params`` header; attrs: every header attribute.
    """

    path: Path
    final: np.ndarray
    transmittance: np.ndarray
    attenuated_surface: np.ndarray
    inscatter: np.ndarray
    single: np.ndarray
    multiple: np.ndarray
    surface: np.ndarray
    stderr: dict[str, np.ndarray]
    surface_coverage: np.ndarray
    distance: np.ndarray
    position: np.ndarray
    view: np.ndarray
    hit_fraction: np.ndarray
    camera: np.ndarray
    sun_direction: np.ndarray | None
    params: dict[str, Any]
    attrs: dict[str, Any] = field(default_factory=dict)
    corr: dict[str, np.ndarray] | None = None

    def __post_init__(self) -> None:
        if self.corr is None:  # a truth built in memory without correlations: its channels' noise is one
            self.corr = {k: np.ones(v.shape) for k, v in self.stderr.items()}

    def __repr__(self) -> str:
        """One line: the file, the size, the samples and the parts (never the arrays).

        >>> from fogref.compare.synthetic import synthetic_truth
        >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
        >>> synthetic_truth(UE4ExponentialHeightFog(UE4FogParams()), shape=(9, 16))
        Truth('<synthetic truth, seed 0>', 16x9 px, 0 spp, seed 0, centre, 64 hit / 80 sky px, no sun)
        """
        h, w = self.shape
        n_hit = int(self.hit.sum())
        sun = "no sun" if self.sun_direction is None else "sun (%.3g, %.3g, %.3g)" % tuple(self.sun_direction)
        seed, pixel_filter = self.attrs.get("fogref.seed", "?"), self.attrs.get("fogref.pixel_filter", "?")
        return (
            f"Truth({str(self.path)!r}, {w}x{h} px, {self.spp} spp, seed {seed}, {pixel_filter}, "
            f"{n_hit} hit / {h * w - n_hit} sky px, {sun})"
        )

    def noise_cov(self, part: str) -> np.ndarray:
        """``(H, W, 3, 3)`` covariance of the noise of part ``part``'s R, G, B at each pixel
        [part units²], from ``stderr`` and ``corr``.

        >>> import numpy as np
        >>> t = Truth.__new__(Truth)
        >>> t.stderr, t.corr = {"inscatter": np.full((1, 1, 3), 2.0)}, {"inscatter": np.full((1, 1, 3), 0.5)}
        >>> t.noise_cov("inscatter")[0, 0].tolist()
        [[4.0, 2.0, 2.0], [2.0, 4.0, 2.0], [2.0, 2.0, 4.0]]
        """
        name = part_attribute(part)
        if name not in self.stderr:
            raise FogrefError(f"{self.path}: no noisy part '{part}' (parts: {', '.join(self.stderr)})")
        corr = self.corr if self.corr is not None else {}
        return covariance(self.stderr[name], corr[name])

    @property
    def hit(self) -> np.ndarray:
        return self.hit_fraction > 0.5

    @property
    def sky(self) -> np.ndarray:
        """``(H, W)`` bool: pixels whose ray escapes."""
        return ~self.hit

    @property
    def shape(self) -> tuple[int, int]:
        return self.hit_fraction.shape

    @property
    def surface_valid(self) -> np.ndarray:
        """``(H, W)`` bool: ``surface`` is defined (some sample reached it)."""
        return self.surface_coverage > 0

    @property
    def pixel_exact(self) -> bool:
        """Every sample of a pixel went through its centre (exact G-buffer and T)."""
        return self.attrs.get("fogref.pixel_filter") == "centre"

    @property
    def spp(self) -> int:
        return int(self.attrs.get("fogref.spp", 0))

    def part(self, name: str) -> np.ndarray:
        """A part by its schema name (``T`` and ``transmittance`` are the same)."""
        if part_group(name) not in PARTS:
            raise FogrefError(f"{self.path}: no part '{name}' (parts: {', '.join(PARTS)})")
        return getattr(self, part_attribute(name))

    def world_positions(self, sky_distance: float) -> np.ndarray:
        """The point each pixel shades [m], as an engine sees it: ``P`` on surfaces,
        ``camera + view * sky_distance`` on sky pixels."""
        if not (np.isfinite(sky_distance) and sky_distance > 0):
            raise FogrefError(f"sky distance: {sky_distance} must be finite and > 0 m")
        far = self.camera + self.view * float(sky_distance)
        return np.where(self.hit[..., None], self.position, far)

    def sun_angle_deg(self) -> np.ndarray | None:
        """``(H, W)`` angle between the view ray and the direction to the sun [deg]; None without a sun."""
        if self.sun_direction is None:
            return None
        return np.degrees(np.arccos(np.clip(self.view @ self.sun_direction, -1.0, 1.0)))

    def identity_residual(self) -> float:
        """Largest ``|final - (attenuated_surface + inscatter)|``: the file's own consistency."""
        return float(np.abs(self.final - (self.attenuated_surface + self.inscatter)).max(initial=0.0))

    def rays(self) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...], np.ndarray]:
        """Per-pixel ``(o, d, D)`` as 3-tuples of flat arrays (``D`` = 1.8e308 for sky)."""
        n = self.hit.size
        o = tuple(np.full(n, c) for c in self.camera)
        v = self.view.reshape(-1, 3)
        D = np.where(self.hit.reshape(-1), self.distance.reshape(-1), np.finfo(np.float64).max)
        return o, tuple(v[:, i] for i in range(3)), D


def covariance(stderr: np.ndarray, corr: np.ndarray) -> np.ndarray:
    """``(..., 3, 3)`` covariance matrices from standard errors ``(..., 3)`` and the
    correlations ``(..., 3)`` of the pairs :data:`CHANNEL_PAIRS` (RG, RB, GB).

    >>> covariance(np.array([1.0, 2.0, 3.0]), np.array([0.5, 0.0, -1.0])).tolist()
    [[1.0, 1.0, 0.0], [1.0, 4.0, -6.0], [0.0, -6.0, 9.0]]
    """
    se = np.asarray(stderr, dtype=np.float64)
    rho = np.broadcast_to(np.asarray(corr, dtype=np.float64), se.shape)
    c = np.zeros(se.shape + (3,))
    for i in range(3):
        c[..., i, i] = se[..., i] ** 2
    for k, (i, j) in enumerate(CHANNEL_PAIRS):
        c[..., i, j] = c[..., j, i] = rho[..., k] * se[..., i] * se[..., j]
    return c


def _vector(source: str, params: dict[str, Any], keys: tuple[str, ...]) -> np.ndarray:
    node: Any = params
    for k in keys:
        if not isinstance(node, dict) or k not in node:
            raise FogrefError(f"{source}: header attribute 'fogref.params' lacks '{'.'.join(keys)}'")
        node = node[k]
    v, name = np.asarray(node, dtype=np.float64), ".".join(keys)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise FogrefError(f"{source}: 'fogref.params' {name} must be 3 finite numbers, got {node!r}")
    return v


def nonfinite_report(channels: dict) -> str | None:
    """None when every channel is finite; else a message with counts and the first pixels."""
    bad = []
    for name, v in channels.items():
        m = ~np.isfinite(np.asarray(v))
        if m.any():
            ys, xs = np.nonzero(m)
            where = ", ".join(f"(x={x}, y={y})" for y, x in list(zip(ys, xs))[:3])
            bad.append(f"'{name}': {int(m.sum())} pixel(s), first at {where}")
    return None if not bad else "non-finite values in " + "; ".join(bad)


def truth_from_channels(channels: dict, attrs: dict, source: str = "<memory>") -> Truth:
    """Build a :class:`Truth` from decoded EXR channels and header attributes.

    Raises FogrefError naming ``source`` for a missing channel, an older or foreign
    layout, a non-finite value, or a missing/malformed ``fogref.params``.
    """
    version = str(attrs.get("fogref.schema", "1"))
    if version not in (str(SCHEMA_VERSION), "2"):
        hint = (
            "it was written by an older fogref (schema 1: no per-pixel noise, surface = Tsurface/T); "
            "render it again"
            if "fogref.version" in attrs
            else "it is not a fogref ground truth"
        )
        raise FogrefError(f"{source}: ground-truth schema {version}, expected {SCHEMA_VERSION}: {hint}")
    # schema 2 has no corr.* channels: its channels' noise is taken as fully correlated (the
    # bound compare used then), and the truth says so (attrs["fogref.noise_correlation"])
    required = [c for c in exr_channel_names() if version != "2" or not c.startswith("corr.")]
    missing = [c for c in required if c not in channels]
    if missing:
        raise FogrefError(
            f"{source}: missing channel(s) {', '.join(repr(c) for c in missing[:8])}"
            f"{' ...' if len(missing) > 8 else ''}"
        )
    bad = nonfinite_report({k: channels[k] for k in required})
    if bad:
        raise FogrefError(f"{source}: refusing a truth with {bad}")
    params = attrs.get("fogref.params")
    if not isinstance(params, dict):
        raise FogrefError(f"{source}: header attribute 'fogref.params' missing or not a JSON object")
    camera = _vector(source, params, ("camera", "origin"))
    sun = None
    if params.get("sun"):
        sun = _vector(source, params, ("sun", "direction"))
        sun = sun / np.linalg.norm(sun)

    def get(name: str) -> np.ndarray:
        a = np.stack([channels[c] for c in channel_names(name)], -1).astype(np.float64)
        return a[..., 0] if not group(name).components else a

    def se(name: str) -> np.ndarray:
        return np.stack([channels[c] for c in stderr_names(name)], -1).astype(np.float64)

    def corr(name: str) -> np.ndarray:
        if version == "2":
            return np.ones(np.shape(channels[stderr_names(name)[0]]) + (3,))
        return np.stack([channels[c] for c in correlation_names(name)], -1).astype(np.float64)

    view = get("view")
    view = view / np.maximum(np.linalg.norm(view, axis=-1, keepdims=True), 1e-30)
    noisy = [g.name for g in GROUPS if g.noisy]
    note = "assumed 1 (schema 2 has no corr.* channels)" if version == "2" else "measured (corr.* channels)"
    attrs = {**attrs, "fogref.noise_correlation": note}
    names = {part_attribute(g.name): g.name for g in GROUPS if g.name not in ("P", "view", "hit")}
    names.update(position="P", hit_fraction="hit")
    return Truth(
        path=Path(source),
        **{f: get(name) for f, name in names.items()},
        view=view,
        camera=camera,
        sun_direction=sun,
        params=params,
        attrs=attrs,
        stderr={part_attribute(g): se(g) for g in noisy},
        corr={part_attribute(g): corr(g) for g in noisy},
    )


def load_truth(path: str | Path) -> Truth:
    """Read and check a ground-truth EXR written by ``fogref render``."""
    channels, attrs = read_exr(path)
    return truth_from_channels(channels, attrs, str(path))

"""``fogref info FILE.exr``: what a ground truth (or any EXR) holds.

Prints the size, the channels (grouped), the header's parameters (fog, sun, sky,
camera), spp, seed, pixel filter, schema, the full camera (origin, target, up, field
of view and its axis, the 4x4 camera-to-world matrix, near/far clip, resolution; the
same in Unreal's coordinates: z-up, left-handed, centimetres, with an FRotator), and
for a fogref truth the noise level of each Monte Carlo part (median and 95th
percentile of the per-pixel relative standard error, and the relative standard error
of the part's image mean).  ``--json``: the same as one JSON object.

Truths written before the header held the whole camera (only ``camera.origin``) get
the rest derived from their ``view.*`` channel (a pinhole fitted to the per-pixel view
directions); near/far clip are then unknown (null).
"""

from __future__ import annotations

import json
import math

import numpy as np

from fogref.errors import FogrefError
from fogref.exrio import read_exr
from fogref.gbuffer import COMPARED_PARTS, truth_from_channels
from fogref.models.ue4 import direction_to_unreal, unreal_rotator, world_to_unreal


def _groups(names) -> list[str]:
    out: dict[str, list[str]] = {}
    for n in sorted(names):
        head, _, tail = n.rpartition(".")
        out.setdefault(head or "(RGB)", []).append(tail)
    return [f"{g}: {','.join(v)}" for g, v in out.items()]


def camera_from_views(view: np.ndarray, origin) -> dict:
    """A pinhole camera fitted to per-pixel unit view directions ``(H, W, 3)`` (world frame).

    Solves ``view(i, j) ∝ [right', up', forward] (u, v, 1)`` (``u = 2 (i + 0.5)/W - 1``,
    ``v = 1 - 2 (j + 0.5)/H``) by linear least squares (the cross product of both sides
    is 0; at most 4096 pixels), then ``fov = 2 atan |right'|`` [deg] (horizontal).  Same
    keys as :func:`fogref.render.load.sensor_camera` except the clip distances (None),
    plus ``mirrored``: True when image x grows along ``up x forward`` (not Mitsuba's
    ``forward x up``: then ``right``, not target/up/fov alone, gives the pixels' directions).

    >>> import numpy as np
    >>> H, W, t = 9, 16, np.tan(np.radians(35))
    >>> u = (np.arange(W) + 0.5) / W * 2 - 1; v = 1 - (np.arange(H) + 0.5) / H * 2
    >>> d = np.stack(np.broadcast_arrays(u[None] * t, v[:, None] * t * H / W, np.ones((H, W))), -1)
    >>> c = camera_from_views(d / np.linalg.norm(d, axis=-1, keepdims=True), [0, 2, 0])
    >>> round(c["fov_deg"], 6), np.round(c["forward"], 6).tolist(), np.round(c["up"], 6).tolist()
    (70.0, [0.0, 0.0, 1.0], [0.0, 1.0, 0.0])
    >>> c["mirrored"]  # here x = u tan(fov/2) grows along up x forward
    True
    """
    H, W, _ = view.shape
    u = (np.arange(W) + 0.5) / W * 2 - 1
    v = 1 - (np.arange(H) + 0.5) / H * 2
    p = np.stack(np.broadcast_arrays(u[None, :], v[:, None], np.ones((H, W))), -1).reshape(-1, 3)
    d = np.asarray(view, dtype=np.float64).reshape(-1, 3)
    keep = np.linspace(0, len(d) - 1, min(len(d), 4096)).astype(int)
    p, d = p[keep], d[keep]
    # d x (M p) = 0, linear in the 9 entries of M (row-major): (d x M p)_k = eps_kab d_a (M p)_b
    A = np.zeros((len(d), 3, 9))
    for k, (a, b) in enumerate(((1, 2), (2, 0), (0, 1))):
        A[:, k, 3 * b : 3 * b + 3] += d[:, a, None] * p
        A[:, k, 3 * a : 3 * a + 3] -= d[:, b, None] * p
    M = np.linalg.svd(A.reshape(-1, 9))[2][-1].reshape(3, 3)
    M /= np.linalg.norm(M[:, 2])
    if M[:, 2] @ d.mean(0) < 0:
        M = -M
    right, up, forward = M[:, 0], M[:, 1], M[:, 2]
    fov = math.degrees(2 * math.atan(np.linalg.norm(right)))
    up = up / np.linalg.norm(up)
    origin = np.asarray(origin, dtype=np.float64)
    to_world = np.eye(4)
    to_world[:3, 0], to_world[:3, 1] = np.cross(up, forward), up
    to_world[:3, 2], to_world[:3, 3] = forward, origin
    return {
        "origin": origin.tolist(),
        "target": (origin + forward).tolist(),
        "up": up.tolist(),
        "forward": forward.tolist(),
        "right": (right / np.linalg.norm(right)).tolist(),
        "fov_deg": fov,
        "fov_axis": "x",
        "fov_y_deg": math.degrees(2 * math.atan(np.linalg.norm(M[:, 1]))),
        "to_world": to_world.tolist(),
        "near_clip": None,
        "far_clip": None,
        "resolution": [W, H],
        "mirrored": bool(right @ np.cross(forward, up) < 0),
    }


def unreal_camera(camera: dict) -> dict:
    """A camera (:func:`fogref.render.load.sensor_camera`'s keys) in Unreal's frame.

    Unreal is z-up, left-handed, centimetres: ``(x, y, z)_ue = 100 (x, z, y)_fogref``
    (:func:`fogref.models.ue4.world_to_unreal`; directions by
    :func:`~fogref.models.ue4.direction_to_unreal`).  ``rotation``: the FRotator
    ``{pitch, yaw, roll}`` [deg] whose X axis is ``forward`` and Z axis ``up``
    (FRotationMatrix).  ``fov_deg``: Unreal's FOV is horizontal, as ``camera["fov_deg"]``.
    """
    origin = world_to_unreal(camera["origin"])
    fwd, up, right = (np.array(direction_to_unreal(camera[k])) for k in ("forward", "up", "right"))
    to_world = np.eye(4)
    to_world[:3, 0], to_world[:3, 1], to_world[:3, 2], to_world[:3, 3] = fwd, right, up, origin
    clip = {k: (None if camera.get(k) is None else camera[k] * 100.0) for k in ("near_clip", "far_clip")}
    return {
        "location_cm": origin.tolist(),
        "target_cm": world_to_unreal(camera["target"]).tolist(),
        "forward": fwd.tolist(),
        "right": right.tolist(),
        "up": up.tolist(),
        "rotation": unreal_rotator(fwd, up),
        "fov_deg": camera["fov_deg"],
        "fov_axis": camera["fov_axis"],
        "to_world": to_world.tolist(),
        "near_clip_cm": clip["near_clip"],
        "far_clip_cm": clip["far_clip"],
        "resolution": camera["resolution"],
    }


def truth_camera(channels: dict, attrs: dict) -> dict | None:
    """The camera of a truth: its header's (``fogref.params`` ``camera``) if complete, else fitted to
    the ``view.*`` channel (:func:`camera_from_views`); ``source`` says which.  None without either."""
    header = attrs.get("fogref.params")
    cam = header.get("camera") if isinstance(header, dict) else None
    if isinstance(cam, dict) and "to_world" in cam:
        return {**cam, "source": "header"}
    names = [f"view.{c}" for c in "XYZ"]
    if not isinstance(cam, dict) or "origin" not in cam or not all(n in channels for n in names):
        return None
    view = np.stack([np.asarray(channels[n], dtype=np.float64) for n in names], -1)
    return {**camera_from_views(view, cam["origin"]), "source": "derived from the view channel"}


def info(path) -> dict:
    """What ``fogref info --json`` prints for ``path``: size, channels, header, camera, noise."""
    channels, attrs = read_exr(path)
    h, w = next(iter(channels.values())).shape if channels else (0, 0)
    out: dict = {"path": str(path), "width": w, "height": h, "channels": sorted(channels), "header": {}}
    for key in HEADER_KEYS:
        if key in attrs:
            out["header"][key[7:]] = attrs[key]
    params = attrs.get("fogref.params")
    out["parameters"] = params if isinstance(params, dict) else None
    cam = truth_camera(channels, attrs) if out["parameters"] else None
    out["camera"] = cam
    out["camera_unreal"] = unreal_camera(cam) if cam else None
    try:
        truth = truth_from_channels(channels, attrs, str(path))
    except FogrefError as e:
        out["truth_error"] = str(e)
        return out
    out["pixels"] = {
        "surface": int(truth.hit.sum()),
        "sky": int(truth.sky.sum()),
        "identity_max_abs": truth.identity_residual(),
    }
    noise = {}
    for part in (*COMPARED_PARTS, "surface"):
        x, se = truth.part(part), truth.stderr[part]
        ok = np.abs(x) > 1e-12
        rel = np.abs(se[ok]) / np.abs(x[ok]) if ok.any() else np.zeros(1)
        mean = float(np.abs(x.mean()))
        noise[part] = {
            "median": float(np.median(rel)),
            "p95": float(np.percentile(rel, 95)),
            "of_mean": float(np.sqrt((se**2).sum()) / x.size / mean) if mean > 0 else 0.0,
        }
    out["noise"] = noise
    return out


_HEADER = "schema spp seed pixel_filter scene scene_sha256 overrides variant version mitsuba"
#: The header attributes ``fogref info`` shows, in this order.
HEADER_KEYS = tuple(f"fogref.{k}" for k in _HEADER.split())


def _vec(v, unit: str = "") -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in v) + ")" + unit


def _camera_lines(cam: dict, ue: dict) -> list[str]:
    clip = "unknown" if cam.get("near_clip") is None else f"{cam['near_clip']:.6g} / {cam['far_clip']:.6g} m"
    lines = [
        f"camera ({cam['source']}; y-up, right-handed, metres):",
        f"  origin {_vec(cam['origin'])}, target {_vec(cam['target'])}, up {_vec(cam['up'])}",
        f"  fov {cam['fov_deg']:.6g} deg ({cam['fov_axis']} axis; {cam['fov_y_deg']:.6g} deg vertical), "
        f"resolution {cam['resolution'][0]}x{cam['resolution'][1]} px, near/far clip {clip}",
        "  to_world " + " ".join(_vec(r) for r in cam["to_world"]),
    ]
    r = ue["rotation"]
    lines += [
        "camera in Unreal (z-up, left-handed, cm):",
        f"  location {_vec(ue['location_cm'])}, rotation (pitch {r['pitch']:.6g}, yaw {r['yaw']:.6g}, "
        f"roll {r['roll']:.6g}) deg, FOV {ue['fov_deg']:.6g} deg (horizontal)",
        f"  forward {_vec(ue['forward'])}, right {_vec(ue['right'])}, up {_vec(ue['up'])}",
    ]
    return lines


def describe(path) -> str:
    """The text ``fogref info`` prints for ``path`` (:func:`info`, as lines).

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from fogref.exrio import write_exr
    >>> p = os.path.join(tempfile.mkdtemp(), "x.exr")
    >>> write_exr(p, {c: np.zeros((2, 3)) for c in "RGB"}, {"fogref.spp": 4})
    >>> print(describe(p).splitlines()[1])
    size: 3x2 px, 3 channels
    """
    d = info(path)
    lines = [f"{path}", f"size: {d['width']}x{d['height']} px, {len(d['channels'])} channels"]
    lines += ["channels:"] + ["  " + g for g in _groups(d["channels"])]
    for k, v in d["header"].items():
        lines.append(f"{k}: {v if isinstance(v, str) else json.dumps(v)}")
    if d["parameters"]:
        lines.append("parameters:")
        for k, v in d["parameters"].items():
            if isinstance(v, dict) and isinstance(v.get("phase"), dict):  # a phase table: its name and size
                ph = v["phase"]
                nodes = len(str(ph.get("cosines", "")).split(","))
                v = {**v, "phase": f"{ph.get('type')} '{ph.get('label')}', {nodes} cosines"}
            lines.append(f"  {k}: {json.dumps(v)}")
    if d["camera"]:
        lines += _camera_lines(d["camera"], d["camera_unreal"])
    if "truth_error" in d:
        lines.append(f"not a readable fogref truth: {d['truth_error']}")
        return "\n".join(lines)
    px = d["pixels"]
    lines.append(
        f"pixels: {px['surface']} surface, {px['sky']} sky; "
        f"identity |final - (attenuated_surface + inscatter)| max {px['identity_max_abs']:.2g}"
    )
    lines.append("noise (relative standard error: per pixel median / p95; of the image mean):")
    for part, n in d["noise"].items():
        lines.append(f"  {part:20s} {n['median']:.3g} / {n['p95']:.3g}; {n['of_mean']:.3g}")
    return "\n".join(lines)

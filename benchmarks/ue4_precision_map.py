"""Where Unreal's own float32 height-fog formula loses accuracy, and fogref's doesn't.

    .venv/bin/python benchmarks/ue4_precision_map.py

Quantity: the optical depth of the camera ray, tau = ln2 * integral with
``integral = CalculateLineIntegralShared(...) * RayLength`` of HeightFogCommon.ush
(one layer, no start distance), computed by fogref's transcription
(:mod:`fogref.models.ue4`: ``fog_constants`` and ``line_integral_shared``,
i.e. the CPU clamps, ``max(-127, Falloff)`` and the Taylor branch
``ln2 - 0.5 ln2^2 Falloff`` below ``|Falloff| <= 0.01``), in float32 (shader)
and in float64 with the Taylor branch kept (the formula's own error without
rounding).  Reference: the exact optical depth of the medium of
:func:`fogref.models.ue4.ue4_to_medium` in mpmath (30 digits).  Compared with
fogref's formulation ``exp_layer_optical_depth`` (numpy float64 and Dr.Jit
float32).  The shader's dimensionless ``Falloff = FogHeightFalloff * dz`` (cm)
is the x axis.

Writes ``reports/stress/ue4_precision.png`` (2-D heat maps of log10 relative
error vs Falloff and camera height / ray length, and 1-D curves across the
Taylor threshold) and ``reports/stress/ue4_precision.json`` (worst errors and
where, per region).
"""

from __future__ import annotations

import json
import math
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import mpmath as mp  # noqa: E402

from fogref.media import NP  # noqa: E402
from fogref.media.closed_form import exp_layer_optical_depth  # noqa: E402
from fogref.models.ue4 import (  # noqa: E402
    FLT_EPSILON2,
    UE4FogParams,
    fog_constants,
    line_integral_shared,
    unreal_to_sigma,
)

mp.mp.dps = 30
OUT = ROOT / "reports" / "stress"
D_EDITOR, F_EDITOR = 0.02, 0.2  # Unreal's defaults: FogDensity, FogHeightFalloff
H_CM = 0.0
LN2 = math.log(2.0)
#: compare where tau_ref < this: fogref saturates the *shape* depth at TAU_MAX = 1e30 (x a ~ 1e-3 /m here)
TAU_VALID = 1e25

try:  # Dr.Jit float32 twin (optional)
    from drjit.llvm import Float

    import fogref
    from fogref.media import drjit_ops

    fogref.ensure_llvm()
    D32 = drjit_ops(Float)
except Exception as exc:  # pragma: no cover - no LLVM here
    D32, Float = None, None
    print("Dr.Jit float32 skipped:", exc)


def shader_tau(cam_z_cm, dz_cm, horiz_cm, dt, taylor=True, params=None):
    """ln2 * Unreal's line integral (one layer), vectorised over dz/horiz; cam_z scalar."""
    p = params or UE4FogParams(FogDensity=D_EDITOR, FogHeightFalloff=F_EDITOR, FogHeight=H_CM)
    C = fog_constants(p, cam_z_cm, dt)
    P = C["P"]
    obs_z = min(dt(cam_z_cm), P[2])
    cz = np.asarray(dz_cm, dt) + (dt(cam_z_cm) - obs_z)
    cx = np.asarray(horiz_cm, dt)
    with np.errstate(all="ignore"):
        length = np.sqrt(cx * cx + cz * cz)
        ro = np.broadcast_to(P[0], length.shape)
        shared = line_integral_shared(P[1], cz, ro, dt, exact=not taylor)
        return (shared * length).astype(np.float64) * LN2


def mp_tau(cam_y, dy, horiz, params=None):
    """Exact optical depth (per the medium of ue4_to_medium), metres in; mpmath."""
    p = params or UE4FogParams(FogDensity=D_EDITOR, FogHeightFalloff=F_EDITOR, FogHeight=H_CM)
    a = mp.mpf(100) * mp.log(2) ** 2 * mp.mpf(p.FogDensity) / 1000
    b = mp.mpf(100) * mp.log(2) * mp.mpf(p.FogHeightFalloff) / 1000
    L = mp.sqrt(mp.mpf(horiz) ** 2 + mp.mpf(dy) ** 2)
    c = a * mp.exp(-b * (mp.mpf(cam_y) - mp.mpf(p.FogHeight) / 100))
    x = b * mp.mpf(dy)
    return c * L if x == 0 else c * L * (-mp.expm1(-x)) / x


def fogref_tau(cam_y, dy, horiz, ops, dt):
    """fogref: sigma * exp_layer_optical_depth(log_c, k, t) (same medium)."""
    a, b = unreal_to_sigma(D_EDITOR, F_EDITOR)
    L = np.sqrt(np.asarray(horiz, np.float64) ** 2 + np.asarray(dy, np.float64) ** 2)
    d = np.asarray(dy, np.float64) / L
    log_c = -b * (np.asarray(cam_y, np.float64) - H_CM / 100) + 0 * L
    if ops is NP:
        tau = exp_layer_optical_depth(NP, log_c, b * d, L)
    else:
        f = lambda v: Float(np.asarray(v, np.float32).ravel())  # noqa: E731
        tau = np.asarray(exp_layer_optical_depth(ops, f(log_c), f(b * d), f(L)).numpy(), np.float64).reshape(
            L.shape
        )
    return np.asarray(tau, np.float64) * np.float32(a) if dt is np.float32 else np.asarray(tau) * a


def rel(x, ref):
    with np.errstate(all="ignore"):
        r = np.abs(x - ref) / ref
    return np.where(np.isfinite(r), r, np.inf)


def worst(err, coords: dict, mask=None):
    e = np.where(mask, err, -1.0) if mask is not None else err
    i = np.unravel_index(int(np.argmax(e)), e.shape)
    return dict(
        worst_rel_error=float(e[i]), at={k: float(np.broadcast_to(v, e.shape)[i]) for k, v in coords.items()}
    )


def main():
    t0 = time.time()
    fall = F_EDITOR / 1000.0  # per cm
    a, b = unreal_to_sigma(D_EDITOR, F_EDITOR)
    OUT.mkdir(parents=True, exist_ok=True)
    report = dict(
        command=".venv/bin/python benchmarks/ue4_precision_map.py",
        params=dict(FogDensity=D_EDITOR, FogHeightFalloff=F_EDITOR, FogHeight_cm=H_CM, a_per_m=a, b_per_m=b),
        quantity="relative error of the ray's optical depth tau = ln2 * LineIntegral * RayLength vs mpmath",
    )

    # ---- 1-D: the line-integral factor g(F) = (1 - 2^-F)/F across the Taylor threshold
    Fpos = np.logspace(-8, math.log10(300.0), 1500)
    F = np.concatenate([-Fpos[::-1], Fpos]).astype(np.float32).astype(np.float64)
    g_ref = np.array(
        [
            float(mp.mpf(1) / mp.log(2)) if f == 0 else float(-mp.expm1(-mp.mpf(f) * mp.log(2)) / mp.mpf(f))
            for f in F
        ]
    )
    curves = {}
    for name, dt, taylor in (
        ("shader float32", np.float32, True),
        ("shader formula float64", np.float64, True),
    ):
        g = line_integral_shared(dt(1.0), F.astype(dt), dt(1.0), dt, exact=not taylor).astype(np.float64)
        curves[name] = rel(g, g_ref)
    # fogref's phi form: g = ln2 * phi(ln2 F)
    from fogref.media.closed_form import phi as cf_phi

    curves["fogref phi float64"] = rel(LN2 * cf_phi(NP, LN2 * F), g_ref)
    if D32 is not None:
        ph = np.asarray(cf_phi(D32, Float((LN2 * F).astype(np.float32))).numpy(), np.float64)
        curves["fogref phi Dr.Jit float32"] = rel(np.float32(LN2) * ph, g_ref)
    th = np.abs(F) <= FLT_EPSILON2
    near = (np.abs(F) > FLT_EPSILON2) & (np.abs(F) <= 0.1)
    clamp = F < -127
    mid = (np.abs(F) > 0.1) & ~clamp
    one_d = {}
    for name, e in curves.items():
        one_d[name] = dict(
            taylor_branch_abs_F_le_0_01=worst(e, dict(Falloff=F), th),
            just_above_threshold_0_01_to_0_1=worst(e, dict(Falloff=F), near),
            abs_F_0_1_to_127=worst(e, dict(Falloff=F), mid),
            below_minus_127_clamp=worst(e, dict(Falloff=F), clamp),
        )
    i_th = np.argmin(np.abs(F - 0.01))
    i_th2 = np.argmin(np.abs(F - 0.0101))
    one_d["at_threshold"] = dict(
        F_taylor=float(F[i_th]),
        shader_float32_taylor=float(curves["shader float32"][i_th]),
        shader_formula_float64_taylor=float(curves["shader formula float64"][i_th]),
        F_division=float(F[i_th2]),
        shader_float32_division=float(curves["shader float32"][i_th2]),
        taylor_truncation_theory=(LN2**2) * 0.01**2 / 6,
    )
    one_d["clamp_minus_127_examples"] = {
        f"F={f}": float(
            rel(
                line_integral_shared(np.float64(1.0), np.float64(f), 1.0, np.float64, True),
                float(-mp.expm1(-mp.mpf(f) * mp.log(2)) / mp.mpf(f)),
            )
        )
        for f in (-128.0, -130.0, -150.0, -200.0)
    }
    report["line_integral_factor_1d"] = one_d

    # ---- 2-D (a): Falloff x camera height; horizontal run 1 km; dz = Falloff / fall
    nF, nH = 161, 121
    Fg = np.concatenate(
        [-np.logspace(math.log10(400), -6, nF // 2), [0.0], np.logspace(-6, math.log10(400), nF // 2)]
    )
    cam_m = np.concatenate([-np.logspace(4.5, -1, nH // 2), [0.0], np.logspace(-1, 6, nH // 2)])
    horiz_m = 1000.0
    dz_cm = Fg / fall
    dz_m = dz_cm / 100.0
    E32 = np.zeros((cam_m.size, Fg.size))
    E64 = np.zeros_like(E32)
    EF64 = np.zeros_like(E32)
    EF32 = np.zeros_like(E32)
    REF = np.zeros_like(E32)
    for i, cy in enumerate(cam_m):
        ref = np.array([float(mp_tau(cy, dzm, horiz_m)) for dzm in dz_m])
        REF[i] = ref
        E32[i] = rel(
            shader_tau(float(np.float32(cy * 100)), dz_cm, np.full_like(dz_cm, horiz_m * 100), np.float32),
            ref,
        )
        E64[i] = rel(shader_tau(cy * 100, dz_cm, np.full_like(dz_cm, horiz_m * 100), np.float64), ref)
        EF64[i] = rel(fogref_tau(cy, dz_m, np.full_like(dz_m, horiz_m), NP, np.float64), ref)
        if D32 is not None:
            EF32[i] = rel(fogref_tau(cy, dz_m, np.full_like(dz_m, horiz_m), D32, np.float32), ref)
    valid = (REF > 1e-30) & (REF < TAU_VALID)
    FF, CC = np.meshgrid(Fg, cam_m)
    obs_clamp = CC * 100 > H_CM + 65536.0
    coll = (-fall * (np.minimum(CC * 100, H_CM + 65536.0) - H_CM) > 126) | (
        -fall * (np.minimum(CC * 100, H_CM + 65536.0) - H_CM) < -125
    )
    fclamp = FF < -127
    clean = valid & ~obs_clamp & ~coll & ~fclamp
    co = dict(Falloff=FF, camera_height_m=CC, tau_ref=REF)
    two_a = dict(
        grid=dict(
            Falloff=[float(Fg.min()), float(Fg.max()), int(Fg.size)],
            camera_height_m=[float(cam_m.min()), float(cam_m.max()), int(cam_m.size)],
            horizontal_run_m=horiz_m,
            valid="tau_ref in [1e-30, 1e25] (fogref saturates shape depth at TAU_MAX = 1e30, T = 0 there)",
        )
    )
    for name, E in (
        ("shader float32", E32),
        ("shader formula float64 (Taylor branch kept)", E64),
        ("fogref float64 numpy", EF64),
        ("fogref float32 Dr.Jit", EF32 if D32 is not None else None),
    ):
        if E is None:
            continue
        two_a[name] = dict(
            no_clamp=worst(E, co, clean),
            no_clamp_taylor=worst(E, co, clean & (np.abs(FF) <= 0.01)),
            no_clamp_division_branch=worst(E, co, clean & (np.abs(FF) > 0.01)),
            observer_clamp=worst(E, co, valid & obs_clamp),
            collapsed_clamp=worst(E, co, valid & coll & ~obs_clamp),
            falloff_minus_127_clamp=worst(E, co, valid & fclamp & ~obs_clamp & ~coll),
        )
    report["map_falloff_x_camera_height"] = two_a

    # ---- 2-D (b): Falloff x ray length (camera at the fog height); ray length sets dz and run
    lengths_m = np.logspace(-4, 7, 111)
    E32b = np.full((lengths_m.size, Fg.size), np.nan)
    EF32b = np.full_like(E32b, np.nan)
    EF64b = np.full_like(E32b, np.nan)
    REFb = np.full_like(E32b, np.nan)
    for i, Lm in enumerate(lengths_m):
        ok = np.abs(dz_m) < Lm
        dzs = dz_m[ok]
        hz = np.sqrt(Lm**2 - dzs**2)
        ref = np.array([float(mp_tau(0.0, d, h)) for d, h in zip(dzs, hz)])
        REFb[i, ok] = ref
        E32b[i, ok] = rel(shader_tau(0.0, dzs * 100, hz * 100, np.float32), ref)
        EF64b[i, ok] = rel(fogref_tau(0.0, dzs, hz, NP, np.float64), ref)
        if D32 is not None:
            EF32b[i, ok] = rel(fogref_tau(0.0, dzs, hz, D32, np.float32), ref)
    FFb, LLb = np.meshgrid(Fg, lengths_m)
    vb = np.isfinite(REFb) & (REFb > 1e-30) & (REFb < TAU_VALID)
    cob = dict(Falloff=FFb, ray_length_m=LLb, tau_ref=REFb)
    two_b = {}
    for name, E in (
        ("shader float32", E32b),
        ("fogref float64 numpy", EF64b),
        ("fogref float32 Dr.Jit", EF32b if D32 is not None else None),
    ):
        if E is None:
            continue
        E = np.where(np.isfinite(E), E, 0.0)
        two_b[name] = dict(
            no_clamp=worst(E, cob, vb & (FFb >= -127)),
            taylor=worst(E, cob, vb & (np.abs(FFb) <= 0.01)),
            falloff_minus_127_clamp=worst(E, cob, vb & (FFb < -127)),
        )
    report["map_falloff_x_ray_length"] = two_b

    # ---- case: where the CPU clamps and -127 matter with a visible T.  Camera just
    # below the observer clamp (FogHeight + 655 m), FogHeightFalloff = 1.9 (collapsed
    # exponent -fall*65500 = -124.5, so the collapsed density D/1000*2^-124.5 is a float32
    # subnormal) and FogHeightFalloff = 2.5 (exponent -163.75 -> clamped at -125),
    # looking straight down so that Falloff = fall*dz runs from -1 to -300.
    case = {}
    for f_ed in (1.9, 2.5):
        pc = UE4FogParams(FogDensity=D_EDITOR, FogHeightFalloff=f_ed, FogHeight=H_CM)
        fl = f_ed / 1000.0
        cam_cm = 65500.0
        rows = []
        for Fv in (-1.0, -10.0, -100.0, -126.0, -127.0, -128.0, -130.0, -140.0, -160.0, -200.0, -300.0):
            dzc = Fv / fl
            ref = mp_tau(cam_cm / 100, dzc / 100, 1e-3, pc)
            t32 = float(shader_tau(cam_cm, np.array([dzc]), np.array([0.1]), np.float32, params=pc)[0])
            t64 = float(
                shader_tau(cam_cm, np.array([dzc]), np.array([0.1]), np.float64, taylor=False, params=pc)[0]
            )
            rows.append(
                dict(
                    Falloff=Fv,
                    tau_ref=float(ref),
                    tau_shader_f32=t32,
                    tau_engine_f64=t64,
                    rel_err_f32=abs(t32 - float(ref)) / float(ref),
                    rel_err_engine_f64=abs(t64 - float(ref)) / float(ref),
                    T_ref=float(mp.exp(-ref)) if ref < 1e4 else 0.0,
                    T_shader_f32=float(np.exp2(np.float32(-t32 / LN2))),
                )
            )
        case[f"FogHeightFalloff={f_ed}"] = dict(
            camera_above_fog_m=cam_cm / 100, collapsed_exponent=-fl * cam_cm, rows=rows
        )
    report["clamp_cases_camera_655m_looking_down"] = case

    # ---- plot
    fig, ax = plt.subplots(2, 2, figsize=(14, 10))
    lg = lambda E: np.log10(np.clip(np.where(np.isfinite(E), E, 1e3), 1e-17, 1e3))  # noqa: E731
    ext = dict(shading="nearest", cmap="magma", vmin=-17, vmax=1)
    im = ax[0, 0].pcolormesh(Fg, cam_m, np.where(valid, lg(E32), np.nan), **ext)
    ax[0, 0].set(
        xscale="symlog",
        yscale="symlog",
        xlabel="Falloff = FogHeightFalloff·Δz (shader, exp2 units)",
        ylabel="camera height above FogHeight [m]",
        title=f"Unreal shader float32: log10 rel. error of τ (run {horiz_m:g} m)",
    )
    ax[0, 0].set_xscale("symlog", linthresh=1e-6)
    ax[0, 0].set_yscale("symlog", linthresh=0.1)
    for x in (-127, -0.01, 0.01):
        ax[0, 0].axvline(x, color="c", lw=0.7, ls="--")
    ax[0, 0].axhline(655.36, color="c", lw=0.7, ls="--")
    ax[0, 0].axhline(-126 / (fall * 100), color="c", lw=0.7, ls=":")
    fig.colorbar(im, ax=ax[0, 0])
    im = ax[0, 1].pcolormesh(Fg, cam_m, np.where(valid, lg(EF32 if D32 is not None else EF64), np.nan), **ext)
    ax[0, 1].set_xscale("symlog", linthresh=1e-6)
    ax[0, 1].set_yscale("symlog", linthresh=0.1)
    ax[0, 1].set(
        xlabel="Falloff (same rays)",
        ylabel="camera height [m]",
        title="fogref exp_layer_optical_depth " + ("Dr.Jit float32" if D32 is not None else "float64"),
    )
    fig.colorbar(im, ax=ax[0, 1])
    im = ax[1, 0].pcolormesh(Fg, lengths_m, np.where(vb, lg(E32b), np.nan), **ext)
    ax[1, 0].set_xscale("symlog", linthresh=1e-6)
    ax[1, 0].set_yscale("log")
    ax[1, 0].set(
        xlabel="Falloff", ylabel="ray length [m]", title="Unreal shader float32, camera at FogHeight"
    )
    for x in (-127, -0.01, 0.01):
        ax[1, 0].axvline(x, color="c", lw=0.7, ls="--")
    fig.colorbar(im, ax=ax[1, 0])
    for name, e in curves.items():
        ax[1, 1].loglog(np.abs(F[F > 0]), np.maximum(e[F > 0], 1e-18), lw=1, label=name + " (F>0)")
        ax[1, 1].loglog(np.abs(F[F < 0]), np.maximum(e[F < 0], 1e-18), lw=1, ls="--", label=name + " (F<0)")
    ax[1, 1].axvline(0.01, color="k", lw=0.7)
    ax[1, 1].axvline(127, color="k", lw=0.7)
    ax[1, 1].set(
        xlabel="|Falloff|",
        ylabel="rel. error of (1-2^-F)/F",
        title="line-integral factor across the Taylor threshold",
        ylim=(1e-18, 1e3),
    )
    ax[1, 1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "ue4_precision.png", dpi=110)
    report["seconds"] = round(time.time() - t0, 1)
    (OUT / "ue4_precision.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=1)[:6000])


if __name__ == "__main__":
    main()

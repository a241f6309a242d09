"""What Henyey–Greenstein and the engines' cosine lobe cost in real (droplet) fog.

For each droplet fog (radiation, advection), visibility and sun elevation, two truths of the
same fog are rendered on the open plane of ``fogref scene`` (camera 2 m up, looking 20 deg
to the right of the sun's azimuth at 24 deg, 70 deg field of view): one with the droplets'
Mie phase, one with HG of the same mean cosine.  Reported (:mod:`fogref.study.droplet_phase`),
each as a relative RMSE of the final image (linear RGB) over its pixels:

* ``hg_final``: HG's truth against Mie's, everything included (multiple scattering), with
  its Monte Carlo standard error;
* ``hg_sun`` and ``lobe_sun``: the sun's single scattering alone with HG or with the engines'
  lobe fitted to HG (closed form, noise-free, no shadows) against the Mie truth's final image.

    .venv/bin/python benchmarks/droplet_phase.py [--res 48 --spp 64 --out reports/droplet_phase]

writes ``results.csv`` and ``README.md`` there (about 15 min on two loaded cores).
"""

from __future__ import annotations

import argparse
import csv
import io
import sys
import tempfile
import time
from pathlib import Path

from _common import ROOT, machine_info  # noqa: F401  (sets the variant, the path)

from fogref.atomic import write_text_atomic
from fogref.gbuffer import load_truth
from fogref.mapping.droplet_fog import droplet_fog
from fogref.mapping.physical import PhysicalScene
from fogref.render.render import render
from fogref.scene.writer import write_scene
from fogref.study.droplet_phase import final_difference, sun_angle, sun_phase_error

DROPLETS = ("radiation", "advection")
VISIBILITY = (150.0, 600.0)  # m, Koschmieder 2 %
ELEVATION = (5.0, 15.0, 35.0, 60.0)  # deg
FALLOFF = 0.02  # 1/m: an e-folding height of 50 m
AUREOLE_DEG = 5.0  # pixels closer to the sun: its aureole (the diffraction peak)


def _truth(tmp: Path, name: str, fog, phase: str, elevation: float, res: int, spp: int):
    df = droplet_fog(fog[0], fog[1], phase=phase, grey=True)
    xml = tmp / f"{name}.xml"
    write_scene(
        xml,
        fog={"sigma_t": list(df.sigma_t), "falloff": FALLOFF},
        albedo=list(df.albedo),
        g=df.g,
        phase=df.phase,
        sun_elevation=elevation,
        sun_azimuth=24.0,
        camera_target=(0.966, 2.2, 1.0),  # azimuth 44 deg: 20 deg right of the sun
        res=res,
        resy=res * 9 // 16,
        on_note=lambda n: None,
        overwrite=True,
    )
    exr = render(xml, tmp / f"{name}.exr", spp=spp, seed=0, progress=False, png=False, resume=False)
    return load_truth(exr)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--res", type=int, default=48)
    ap.add_argument("--only", action="store_true", help="one configuration (a smoke run)")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--out", default=str(ROOT / "reports" / "droplet_phase"))
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    t0 = time.time()
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        grid = [(d, v, e) for d in DROPLETS for v in VISIBILITY for e in ELEVATION]
        for drops, V, el in grid[:1] if a.only else grid:
            mie = _truth(tmp, "mie", (V, drops), "mie", el, a.res, a.spp)
            hg = _truth(tmp, "hg", (V, drops), "hg", el, a.res, a.spp)
            pf = PhysicalScene.from_params(mie.params)
            away = sun_angle(mie, pf.sun_direction) >= AUREOLE_DEG
            fd, fd_away = final_difference(mie, hg), final_difference(mie, hg, away)
            row = {
                "droplets": drops,
                "visibility_m": V,
                "sun_elevation_deg": el,
                "g": round(pf.medium.g, 4),
                "hg_final": fd["rel_rmse"],
                "hg_final_stderr": fd["stderr"],
                "hg_sun": sun_phase_error(mie, pf, "hg")["rel_rmse"],
                "lobe_sun": sun_phase_error(mie, pf, "lobe")["rel_rmse"],
                "away_pixels": int(away.sum()),
                "hg_final_away": fd_away["rel_rmse"],
                "hg_final_away_stderr": fd_away["stderr"],
                "hg_sun_away": sun_phase_error(mie, pf, "hg", away)["rel_rmse"],
                "lobe_sun_away": sun_phase_error(mie, pf, "lobe", away)["rel_rmse"],
                "aureole_pixels": int((~away).sum()),
                "aureole_hg_ratio": sun_phase_error(mie, pf, "hg", ~away)["mean_ratio"],
                "aureole_lobe_ratio": sun_phase_error(mie, pf, "lobe", ~away)["mean_ratio"],
            }
            rows.append(row)
            print({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in row.items()}, flush=True)
    buf = io.StringIO()
    wr = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    wr.writeheader()
    wr.writerows(rows)
    write_text_atomic(out / "results.csv", buf.getvalue())
    pct = lambda x: f"{100 * x:.1f} %"  # noqa: E731
    lines = [
        "# What Henyey-Greenstein and the engines' lobe cost in droplet fog",
        "",
        f"Written by `benchmarks/droplet_phase.py --res {a.res} --spp {a.spp}` "
        f"({time.time() - t0:.0f} s; {machine_info().get('cpu', 'CPU')}, LLVM back end).",
        "",
        f"Open plane, exponential fog (falloff {FALLOFF} /m) whose extinction at the ground gives the "
        "visibility V (Koschmieder, 2 %, green; grey extinction), albedo from Mie; sun azimuth 24 deg, "
        "camera 2 m up looking 8 deg up and 20 deg right of the sun, 70 deg field of view, "
        f"{a.res}x{a.res * 9 // 16} pixels (pixel centres), {a.spp} spp, seed 0. Two truths per row: "
        "the droplets' Mie phase and HG of the same mean cosine g.",
        "",
        "Relative RMSE of the final image (linear RGB) against the Mie truth, over all pixels and over "
        f"those at least {AUREOLE_DEG:g} deg from the sun (`away`): `HG truth` is the HG truth's "
        "(everything, multiple scattering included; +- its Monte Carlo standard error, the noise "
        "removed); `HG sun`, `lobe sun` count the sun's single scattering alone, with HG or with the "
        "engines' cosine lobe fitted to HG (closed form, noise-free, no shadows). `aureole HG`, "
        f"`aureole lobe`: within {AUREOLE_DEG:g} deg of the sun (when in view), the substitute's mean "
        "sun single scattering over the droplets'.",
        "",
        "| droplets | V [m] | sun [deg] | g | HG truth | HG sun | lobe sun | HG truth, away | HG sun, away "
        "| lobe sun, away | aureole HG | aureole lobe |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        aur = r["aureole_pixels"] > 0
        lines.append(
            f"| {r['droplets']} | {r['visibility_m']:g} | {r['sun_elevation_deg']:g} | {r['g']:.3f} | "
            f"{pct(r['hg_final'])} +- {pct(r['hg_final_stderr'])} | {pct(r['hg_sun'])} | "
            f"{pct(r['lobe_sun'])} | "
            f"{pct(r['hg_final_away'])} +- {pct(r['hg_final_away_stderr'])} | {pct(r['hg_sun_away'])} | "
            f"{pct(r['lobe_sun_away'])} | "
            + (f"{r['aureole_hg_ratio']:.3f} | {r['aureole_lobe_ratio']:.3f} |" if aur else "- | - |")
        )
    write_text_atomic(out / "README.md", "\n".join(lines) + "\n")
    print(out / "README.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Bad-input harness: each case through the `fogref` command of a checkout, classified.

usage: python benchmarks/bad_input.py CHECKOUT LABEL [WORKDIR]
    CHECKOUT: a fogref checkout with its .venv (this one: .); LABEL: the name of the result
    (e.g. "after", or "aa24502" for an older clone); WORKDIR: scratch folder (default a temp dir).
Writes reports/bad_input/LABEL.json and rewrites reports/bad_input/summary.md from every
LABEL.json there.  Outcomes: refused (exit 2, a 'fogref: error' line, no traceback),
traceback, accepted (exit 0), rc1/rc3 (a comparison ran), hang (no exit in 240 s).  A case is
good when its outcome is the expected one (refused, or accepted for the valid controls).
"""

import itertools
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
from collections import Counter
from pathlib import Path

REPORTS = Path(__file__).resolve().parents[1] / "reports" / "bad_input"
clone = Path(sys.argv[1]).resolve()
LABEL = sys.argv[2]
W = Path(sys.argv[3]).resolve() if len(sys.argv) > 3 else Path(tempfile.mkdtemp(prefix="fogref-bad-input-"))
shutil.rmtree(W, ignore_errors=True)
W.mkdir(parents=True)
FOG = str(clone / ".venv/bin/fogref")
os.chdir(W)
valley = str(clone / "scenes/valley.xml")
tiny = ["--set", "res=8", "--set", "resy=6", "--spp", "1", "--quiet"]
env = dict(os.environ, PYTHONPATH=str(W))


def run(args, timeout=240):
    try:
        p = subprocess.run([FOG, *args], capture_output=True, text=True, timeout=timeout, env=env)
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        return None, "", ""


# fixtures
rc, out, err = run(["render", valley, *tiny, "--out", "t.exr"])
assert rc == 0, err
Path("garbage.exr").write_text("not an exr")
Path("noparts").mkdir()
vx = Path(valley).read_text()

Path("nofog.xml").write_text(
    re.sub(r"<medium type=\"heightfog\".*?</medium>", "", vx, flags=re.S).replace(
        "scenes/", str(clone / "scenes") + "/"
    )
)
two = vx.replace(
    "</scene>",
    '<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
    '<integer name="height" value="6"/></film></sensor></scene>',
)
Path("twosensors.xml").write_text(two)
Path("bad_model.py").write_text(
    textwrap.dedent("""
    import numpy as np
    from fogref.models.base import FogResult
    class NoneFog:
        def evaluate(self, camera, positions, precision="float32"): return None
    class StrFog:
        def evaluate(self, camera, positions, precision="float32"): return "a", "b"
    class RaiseFog:
        def evaluate(self, camera, positions, precision="float32"): raise RuntimeError("boom")
    class HugeFog:
        def evaluate(self, camera, positions, precision="float32"):
            s = positions.shape[:-1]
            return FogResult(inscatter=np.full(s + (3,), 1e300), transmittance=np.ones(s + (3,)))
    def __getattr__(name): raise ImportError("lazy")
""")
)


def hdr(name, header, w=8, h=6, body=True):
    data = header.encode()
    if body:
        data += b"\x00" * (w * h * 4)
    Path(name).write_bytes(data)


hdr("badexp.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=abc\n\n-Y 6 +X 8\n")
hdr("badres.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y six +X 8\n")
hdr("neg.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y -6 +X 8\n")
hdr("huge.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000000 +X 100000000\n", body=False)
base_toml = (
    open(clone / "reports/sweeps/unreal_sun_falloff_g/SWEEP.toml")
    .read()
    .replace('"scenes/valley.xml"', json.dumps(valley))
    .replace("res = 64, resy = 36", "res = 8, resy = 6")
    .replace("spp = 16", "spp = 1")
    .replace("values = [4, 10, 20, 40]", "values = [4, 10]")
    .replace("values = [0.05, 0.1, 0.2, 0.4]", "values = [0.1]")
    .replace("values = [0.3, 0.6, 0.85]", "values = [0.6]")
    .replace("plots = true", "plots = false")
)


def toml(name, old, new):
    t = base_toml.replace(old, new)
    assert old in base_toml or old == "", (name, old)
    t = t.replace("[sweep]", '[sweep]\nout = "sw_' + name.replace(".", "_") + '"', 1)
    Path(name).write_text(t)
    return name


C = []  # (id, args, expect)  expect: 'refuse' or 'ok'
R = lambda *a: ["render", valley, *tiny, "--out", "o.exr", *a]
C += [
    ("render sun_elevation=1000", R("--set", "sun_elevation=1000"), "refuse"),
    ("render checkpoint-seconds -1", R("--checkpoint-seconds", "-1"), "refuse"),
    ("render checkpoint-seconds nan", R("--checkpoint-seconds", "nan"), "refuse"),
    ("render --spp twice", R("--spp", "8"), "refuse"),
    ("render --set twice", R("--set", "res=9"), "refuse"),
    ("render variant scalar_rgb", R("--variant", "scalar_rgb"), "refuse"),
    ("render variant cuda without CUDA", R("--variant", "cuda_ad_rgb"), "refuse"),
    ("render max_depth=0", R("--set", "max_depth=0"), "refuse"),
    (
        "render spp 0",
        ["render", valley, "--set", "res=8", "--set", "resy=6", "--spp", "0", "--quiet", "--out", "o.exr"],
        "refuse",
    ),
    (
        "render spp -5",
        ["render", valley, "--set", "res=8", "--set", "resy=6", "--spp", "-5", "--quiet", "--out", "o.exr"],
        "refuse",
    ),
    (
        "render res=0",
        ["render", valley, "--set", "res=0", "--set", "resy=6", "--spp", "1", "--quiet", "--out", "o.exr"],
        "refuse",
    ),
    ("render unknown --set", R("--set", "sun_elevaton=10"), "refuse"),
    ("render sigma_t=nan", R("--set", "sigma_t=nan"), "refuse"),
    ("render g=1.5", R("--set", "g=1.5"), "refuse"),
    ("render falloff=-1", R("--set", "falloff=-1"), "refuse"),
    ("render missing scene", ["render", "nope.xml", "--out", "o.exr"], "refuse"),
    ("render no fog medium", ["render", "nofog.xml", *tiny, "--out", "o.exr"], "refuse"),
    ("render two sensors", ["render", "twosensors.xml", *tiny, "--out", "o.exr"], "refuse"),
    (
        "render --out = scene",
        ["render", str(W / "twosensors.xml"), *tiny, "--out", str(W / "twosensors.xml")],
        "refuse",
    ),
    ("render --out dir", ["render", valley, *tiny, "--out", "noparts"], "refuse"),
    ("render ok", R(), "ok"),
]
M = lambda *a: ["compare", "t.exr", "--model", "ue4", "--from-scene", "--out", "cmp", *a]
I = lambda *a: ["compare", "t.exr", "--image", "t.exr", "--out", "cmpi", *a]
C += [
    ("compare --image + --from-scene", I("--from-scene"), "refuse"),
    ("compare --image + --param", I("--param", "FogDensity=0.02"), "refuse"),
    ("compare --image + --precision", I("--precision", "float64"), "refuse"),
    ("compare --model + --exposure", M("--exposure", "2"), "refuse"),
    ("compare --model + --encoding", M("--encoding", "srgb"), "refuse"),
    ("compare param lobe exponent -5", M("--param", "DirectionalInscatteringExponent=-5"), "refuse"),
    ("compare param SunLuminance -1", M("--param", "SunLuminance=-1"), "refuse"),
    ("compare param colour -1", M("--param", "FogInscatteringColor=[-1,0,0]"), "refuse"),
    ("compare param FogHeight 1e400", M("--param", "FogHeight=1e400"), "refuse"),
    ("compare unknown model", ["compare", "t.exr", "--model", "ue44", "--out", "cmp"], "refuse"),
    (
        "compare garbage truth",
        ["compare", "garbage.exr", "--model", "ue4", "--from-scene", "--out", "cmp"],
        "refuse",
    ),
    (
        "compare model returns None",
        ["compare", "t.exr", "--model", "bad_model:NoneFog", "--out", "cmp"],
        "refuse",
    ),
    (
        "compare model returns strings",
        ["compare", "t.exr", "--model", "bad_model:StrFog", "--out", "cmp"],
        "refuse",
    ),
    ("compare model raises", ["compare", "t.exr", "--model", "bad_model:RaiseFog", "--out", "cmp"], "refuse"),
    (
        "compare module getattr ImportError",
        ["compare", "t.exr", "--model", "bad_model:Missing", "--out", "cmp"],
        "refuse",
    ),
    ("compare hdr bad EXPOSURE", ["compare", "t.exr", "--image", "badexp.hdr", "--out", "cmph"], "refuse"),
    ("compare hdr bad resolution", ["compare", "t.exr", "--image", "badres.hdr", "--out", "cmph"], "refuse"),
    ("compare hdr negative height", ["compare", "t.exr", "--image", "neg.hdr", "--out", "cmph"], "refuse"),
    ("compare hdr 1e8x1e8", ["compare", "t.exr", "--image", "huge.hdr", "--out", "cmph"], "refuse"),
    ("compare model 1e300", ["compare", "t.exr", "--model", "bad_model:HugeFog", "--out", "cmp"], "refuse"),
    ("compare --tolerance twice", M("--tolerance", "T=0.1", "--tolerance", "T=0.2"), "refuse"),
    ("compare ok", M(), "any"),
]

_n = itertools.count()
S = lambda *a: ["scene", "--out", f"w{next(_n)}.xml", *a]
C += [
    ("scene sun-elevation 95", S("--sun-elevation", "95"), "refuse"),
    ("scene ue max opacity 5", S("--ue-fog-max-opacity", "5"), "refuse"),
    ("scene geometry missing.obj", S("--geometry", "missing.obj"), "refuse"),
    ("scene ok", S(), "ok"),
]
SW = lambda f, *a: ["sweep", f, "--quiet", *a]
C += [
    ("sweep workers 0", SW(toml("a.toml", "", ""), "--workers", "0"), "refuse"),
    ("sweep workers -1", SW("a.toml", "--workers", "-1"), "refuse"),
    ("sweep drjit-threads -1", SW("a.toml", "--drjit-threads", "-1"), "refuse"),
    ("sweep scheduler garbage", SW("a.toml", "--scheduler", "garbage"), "refuse"),
    ("sweep duplicate grid values", SW(toml("dup.toml", "values = [4, 10]", "values = [4, 4]")), "refuse"),
    (
        "sweep pixel_filter gauss",
        SW(toml("pf.toml", "seed = 0", 'seed = 0\npixel_filter = "gauss"')),
        "refuse",
    ),
    ("sweep wrong value type", SW(toml("ty.toml", "values = [0.6]", 'values = ["a", 0.6]')), "refuse"),
    (
        "sweep unknown model param",
        SW(toml("um.toml", "from_scene = true", "from_scene = true\nparams = { Bogus = 1 }")),
        "refuse",
    ),
    (
        "sweep table escapes out",
        SW(toml("te.toml", 'table = "results"', 'table = "../../escaped"')),
        "refuse",
    ),
    ("sweep res 0", SW(toml("r0.toml", "res = 8, resy = 6", "res = 0, resy = 6")), "refuse"),
    (
        "sweep sigma_t 1e9",
        SW(toml("st.toml", "values = [0.6]", "values = [0.3]\n[parameters.sigma_t]\nvalues = [1e9]")),
        "refuse",
    ),
    ("sweep seed x", SW(toml("sx.toml", "seed = 0", 'seed = "x"')), "refuse"),
    (
        "sweep swept and fixed",
        SW(toml("sf.toml", "res = 8, resy = 6", "res = 8, resy = 6, g = 0.5")),
        "refuse",
    ),
    (
        "sweep two labels one target",
        SW(
            toml("tl.toml", "[parameters.g]", '[parameters.g2]\ntarget = "g"\nvalues = [0.1]\n[parameters.g]')
        ),
        "refuse",
    ),
    (
        "sweep huge grid",
        SW(
            toml(
                "hg.toml",
                "values = [0.6]",
                "values = ["
                + ",".join(str(0.001 * i) for i in range(1000))
                + "]\n[parameters.albedo]\nvalues = ["
                + ",".join(str(0.0001 * i) for i in range(1000))
                + "]\n[parameters.fov]\nvalues = ["
                + ",".join(str(10 + 0.01 * i) for i in range(1000))
                + "]",
            )
        ),
        "refuse",
    ),
]
C += [
    ("info garbage", ["info", "garbage.exr"], "refuse"),
    ("info missing", ["info", "missing.exr"], "refuse"),
]

rows = []
for cid, args, expect in C:
    rc, out, err = run(args)
    tb = "Traceback" in err or "Traceback" in out
    if rc is None:
        outcome = "hang"
    elif tb:
        outcome = "traceback"
    elif rc == 2 and "error" in err:
        outcome = "refused"
    elif rc == 0:
        outcome = "accepted"
    else:
        outcome = f"rc{rc}"
    good = (
        (outcome == "refused")
        if expect == "refuse"
        else (outcome in ("accepted", "rc1", "rc3") if expect == "any" else outcome == "accepted")
    )
    last = (err.strip().splitlines() or [""])[-1][:160]
    rows.append(dict(case=cid, outcome=outcome, good=good, message=last))
    print(f"{'OK ' if good else 'BAD'} {outcome:9s} {cid:38s} {last}", flush=True)

print(Counter(r["outcome"] for r in rows), "good", sum(r["good"] for r in rows), "/", len(rows))
REPORTS.mkdir(parents=True, exist_ok=True)
json.dump(rows, open(REPORTS / f"{LABEL}.json", "w"), indent=1)
runs = {p.stem: json.load(open(p)) for p in sorted(REPORTS.glob("*.json"))}
md = [
    "# Bad input through the `fogref` command",
    "",
    "Made by `python benchmarks/bad_input.py CHECKOUT LABEL` (one run per checkout). A case is good when",
    "it is refused in one line with exit 2 (or, for the valid controls, accepted).",
    "",
    "| run | cases | good | refused | accepted | traceback | hang | other |",
    "|---|---|---|---|---|---|---|---|",
]
for label, rs in runs.items():
    c = Counter(r["outcome"] for r in rs)
    other = sum(v for k, v in c.items() if k not in ("refused", "accepted", "traceback", "hang"))
    md.append(
        f"| {label} | {len(rs)} | {sum(r['good'] for r in rs)} | {c['refused']} | {c['accepted']} | "
        f"{c['traceback']} | {c['hang']} | {other} |"
    )
md += ["", "| case | " + " | ".join(runs) + " |", "|---|" + "---|" * len(runs)]
cases = list(dict.fromkeys(r["case"] for rs in runs.values() for r in rs))
by = {label: {r["case"]: r for r in rs} for label, rs in runs.items()}
for case in cases:
    cells = [
        (by[l][case]["outcome"] + ("" if by[l][case]["good"] else " ✗")) if case in by[l] else "—"
        for l in runs
    ]
    md.append(f"| {case} | " + " | ".join(cells) + " |")
(REPORTS / "summary.md").write_text("\n".join(md) + "\n")

"""``fogref scene --out S.xml``: write a scene XML from fog, sun, sky, camera and geometry.

The work, and the checks of every value with its range, is
:func:`fogref.scene.writer.write_scene`; its defaults are the options' defaults.
Fog is given either in physical units or as Unreal editor values, not both.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, make_dataclass

from fogref.cli.checks import Choice, Integer, Number, PathArg, Text
from fogref.cli.spec import UsageError, api_arguments, option, switch, toggle
from fogref.mapping.droplet_fog import PHASES, droplet_fog
from fogref.mapping.unreal_pathtracer import DROPPED, exact_fog_params, rewrite_scene, validated_settings
from fogref.media.droplets import DROPLET_PRESETS
from fogref.models.ue4 import UE4FogParams
from fogref.scene.fog_input import UNREAL_IGNORED, UNREAL_IGNORED_RANGES, UNREAL_MAPPED, flat_unreal
from fogref.scene.templates import MESH_UP
from fogref.scene.vocabulary import PHYSICAL, RANGES, SCATTERING, SOURCE
from fogref.scene.writer import write_scene

NAME = "scene"
HELP = "write a scene XML from fog (physical or Unreal values), sun, sky, camera and geometry"
DESCRIPTION = (
    "Write a fogref scene XML (fogpath integrator, heightfog medium) that fogref render takes as is. "
    "All values are checked; every fog, sun, sky and camera value becomes an XML $default that "
    "`fogref render --set` can change.  fogref is y-up, metres; Unreal values are z-up, centimetres."
)
EPILOG = "exit codes: 0 written, 2 usage or input error"
WRITE = "fogref.scene.writer:write_scene"
GEOMETRY = "geometry"
PHYS = "fog in physical units (y-up, metres)"
UE = (
    "fog as Unreal editor values (Exponential Height Fog; z-up, centimetres), mapped exactly: "
    "sigma_t = 100 (ln 2)^2 FogDensity/1000 /m, falloff = 100 ln 2 FogHeightFalloff/1000 /m"
)
SCAT = "scattering (both fog inputs; Unreal has none)"
PT = (
    "Unreal's path-traced fog (UE 5.x PathTracing.cpp: the Unreal fog values above with the clamp and "
    "the camera-centred cylinder; fogref/mapping/unreal_pathtracer.py)"
)
#: ``--ue-*`` option -> UEPathTracerSettings field (fogref.mapping.unreal_pathtracer.SETTING_RANGES)
PT_OPTIONS = {
    "--ue-volumetric-fog-distance": "VolumetricFogDistance",
    "--ue-volumetric-fog-extinction-scale": "VolumetricFogExtinctionScale",
    "--ue-volumetric-fog-albedo": "VolumetricFogAlbedo",
    "--ue-volumetric-fog-scattering-distribution": "VolumetricFogScatteringDistribution",
    "--ue-fog-density-clamp": "FogDensityClamp",
}
DROPS = (
    "fog from visibility and droplets (replace --sigma-t, --albedo and --g; the droplets' Mie optics: "
    "fogref/mapping/droplet_fog.py)"
)
LIGHT = "sun and sky"
LFV = (
    "a Local Fog Volume whose density adds to the fog's: a sphere, density "
    "D max(1 - |p - C|^2 / R^2, 0) exp(-F (y - H)) times --sigma-t (fogref/media/local_fog_volume.py)"
)
CAMERA = "camera (y-up, metres)"


def _range(table: dict, name: str) -> str:
    """``in [lo, hi] unit`` of a value of the PHYSICAL, SCATTERING or RANGES table."""
    return f"in {table[name].text()}"


def _dest(option_name: str) -> str:
    return option_name.lstrip("-").replace("-", "_")


def _ue_option(key: str) -> str:
    return UNREAL_MAPPED.get(key) or UNREAL_IGNORED[key][0]


def _number(help: str, group: str, default_text: str | None = None):
    """A number option that write_scene checks (its range is in ``help``), None unless given."""
    return option(None, help, check=Number(), group=group, default_text=default_text)


@dataclass
class _Options:
    out: str = option(help="scene file to write (.xml)", check=PathArg(role="output"), metavar="S.xml")
    force: bool = switch("replace an existing --out", api=WRITE, api_name="overwrite")
    geometry: str = option(
        "plane",
        "plane (ground plane), valley (the shipped valley's ridges) or a mesh file "
        "(.obj/.ply, loaded by Mitsuba)",
        group=GEOMETRY,
        api=WRITE,
    )
    mesh_scale: float = option(
        1.0,
        "metres per mesh file unit (1: the file is in metres; 0.01 for centimetres)",
        check=Number(),
        group=GEOMETRY,
        api=WRITE,
    )
    mesh_up: str = option(
        "y",
        "the mesh file's frame (y: y-up; z: z-up, rotated -90 deg about +x; unreal: "
        "Unreal's z-up left-handed frame, y and z swapped like fogref's Unreal position mapping)",
        check=Choice(MESH_UP),
        group=GEOMETRY,
        api=WRITE,
    )
    mesh_translate: tuple = option(
        (0.0, 0.0, 0.0),
        "offset [m] applied after scale and rotation",
        check=Text(),
        metavar="X,Y,Z",
        group=GEOMETRY,
        api=WRITE,
    )
    ground: bool | None = toggle(
        "a ground plane at y = 0",
        group=GEOMETRY,
        api=WRITE,
        default_text="on for plane/valley, off for a mesh",
    )
    ground_size: float | None = option(
        None,
        "half-size of the ground plane [m]",
        check=Number(),
        group=GEOMETRY,
        api=WRITE,
        default_text="1e5; valley 3000",
    )
    sigma_t: str | None = option(
        None,
        f"extinction at --height, grey or RGB, {_range(PHYSICAL, 'sigma_t')}",
        check=Text(),
        metavar="S|R,G,B",
        group=PHYS,
        default_text="the valley's, Unreal FogDensity 0.02",
    )
    falloff: float | None = _number(f"height falloff, {_range(PHYSICAL, 'falloff')}", PHYS, "0.0138629")
    height: float | None = _number(f"reference height of --sigma-t, {_range(PHYSICAL, 'height')}", PHYS, "0")
    density: float | None = _number(f"relative density of layer 1, {_range(PHYSICAL, 'density')}", PHYS, "1")
    density2: float | None = _number(
        f"second layer: density relative to --sigma-t, {_range(PHYSICAL, 'density2')}", PHYS, "0: none"
    )
    falloff2: float | None = _number(f"second layer: falloff, {_range(PHYSICAL, 'falloff2')}", PHYS, "0.002")
    height2: float | None = _number(
        f"second layer: reference height, {_range(PHYSICAL, 'height2')}", PHYS, "100"
    )
    bounds_min: str | None = option(
        None, "fog box: lower corner [m]", check=Text(), metavar="X,Y,Z", group=PHYS
    )
    bounds_max: str | None = option(
        None, "fog box: upper corner [m]", check=Text(), metavar="X,Y,Z", group=PHYS
    )
    lfv_centre: str | None = option(
        None, "the volume's centre C [m]", check=Text(), metavar="X,Y,Z", group=LFV, default_text="0,0,0"
    )
    lfv_radius: float | None = _number(
        f"its radius R, {_range(PHYSICAL, 'lfv_radius')}; gives the volume", LFV
    )
    lfv_density: float | None = _number(f"D, {_range(PHYSICAL, 'lfv_density')}", LFV, "1")
    lfv_falloff: float | None = _number(f"F, {_range(PHYSICAL, 'lfv_falloff')}", LFV, "0")
    lfv_height: float | None = _number(f"H, {_range(PHYSICAL, 'lfv_height')}", LFV, "0")
    visibility: float | None = option(
        None,
        "meteorological optical range at --height: the green channel's extinction is -ln(contrast) / V",
        check=Number(0.0, 1e6, lo_open=True, unit="m"),
        group=DROPS,
    )
    contrast: float = option(
        0.02,
        "the visibility's contrast threshold: 0.02 (Koschmieder, Bevy: 3.912/V) or 0.05 (WMO: 2.996/V)",
        check=Number(0.0, 1.0, lo_open=True, hi_open=True),
        group=DROPS,
    )
    droplets: str | None = option(
        None,
        "droplet size distribution: radiation or advection fog (Shettle & Fenn 1979); without "
        "--visibility their own droplet number sets it (Mie optics: about 1 s of CPU for radiation "
        "fog, 25 s for advection fog's larger drops)",
        check=Choice(tuple(sorted(DROPLET_PRESETS))),
        group=DROPS,
    )
    phase: str | None = option(
        None,
        "phase function: mie (the droplets'), approx-mie (Jendersie & d'Eon's fit) or hg (of the Mie "
        "mean cosine)",
        check=Choice(PHASES),
        group=DROPS,
        default_text="mie with --droplets, else hg of --g",
    )
    grey_extinction: bool = switch(
        "the green channel's extinction for R, G and B (engines with grey extinction need it; droplet "
        "extinction is grey within about 2 %)",
        group=DROPS,
    )
    ue_fog_density: float | None = _number("Fog Density", UE, "0.02")
    ue_fog_height_falloff: float | None = _number("Fog Height Falloff", UE, "0.2")
    ue_fog_height: float | None = _number("the fog's world Z [cm]: y = Z/100 m", UE, "0")
    ue_second_fog_density: float | None = _number("Second Fog Data: Fog Density", UE, "0")
    ue_second_fog_height_falloff: float | None = _number("Second Fog Data: Fog Height Falloff", UE, "0.2")
    ue_second_fog_height_offset: float | None = _number("Second Fog Data: Fog Height Offset [cm]", UE, "0")
    ue_pathtracer: bool = switch(
        "write the fog Unreal's path tracer renders for the Unreal values (profile ue_pathtracer: "
        "density x extinction scale, clamped below the fog height, inside a cylinder centred on the "
        "camera) instead of the exact fog",
        group=PT,
    )
    ue_exact: bool = switch(
        "as --ue-pathtracer, but the same fog without the clamp and the cylinder (the physics the path "
        "tracer approximates: its density, falloffs, heights, albedo and g, unbounded)",
        group=PT,
    )
    ue_volumetric_fog_distance: float | None = _number(
        "VolumetricFogDistance: the cylinder's radius [cm], [0.1, 1e9]", PT, "6000"
    )
    ue_volumetric_fog_extinction_scale: float | None = _number(
        "VolumetricFogExtinctionScale: multiplies the density, >= 0", PT, "1"
    )
    ue_volumetric_fog_albedo: str | None = option(
        None,
        "VolumetricFogAlbedo: linear RGB (or grey) in [0, 1]",
        check=Text(),
        metavar="A|R,G,B",
        group=PT,
        default_text="1",
    )
    ue_volumetric_fog_scattering_distribution: float | None = _number(
        "VolumetricFogScatteringDistribution: the HG g, [-0.99, 0.99]", PT, "0.2"
    )
    ue_fog_density_clamp: float | None = _number(
        "r.PathTracing.FogDensityClamp: the density's growth below the fog height, in multiples of "
        "the fog density, [1, 256]",
        PT,
        "8",
    )
    albedo: str | None = option(
        None,
        f"single-scattering albedo, grey or RGB, {_range(SCATTERING, 'albedo')}",
        check=Text(),
        metavar="A|R,G,B",
        group=SCAT,
        api=WRITE,
        default_text="0.9",
    )
    g: float | None = option(
        None,
        f"Henyey-Greenstein g, {_range(SCATTERING, 'g')}",
        check=Number(),
        group=SCAT,
        api=WRITE,
        default_text="0.6",
    )
    max_depth: int = option(
        16,
        f"path depth (2 = single scattering, -1 = no limit), {_range(RANGES, 'max_depth')}",
        check=Integer(),
        group=SCAT,
        api=WRITE,
    )
    sun_elevation: float = option(
        8.0,
        f"sun above the horizon, {_range(RANGES, 'sun_elevation')}",
        check=Number(),
        group=LIGHT,
        api=WRITE,
    )
    sun_azimuth: float = option(
        24.0,
        f"sun azimuth from +z toward +x, {_range(RANGES, 'sun_azimuth')}",
        check=Number(),
        group=LIGHT,
        api=WRITE,
    )
    sun_irradiance: tuple = option(
        (3.2, 2.9, 2.4),
        f"sun irradiance, grey or linear RGB, {_range(RANGES, 'sun_irradiance')}",
        check=Text(),
        metavar="E|R,G,B",
        group=LIGHT,
        api=WRITE,
    )
    sky_radiance: tuple | None = option(
        (0.2, 0.3, 0.5),
        f"uniform sky radiance, grey or linear RGB, {_range(RANGES, 'sky_radiance')}, or none (black)",
        check=Text(),
        metavar="L|R,G,B|none",
        group=LIGHT,
        api=WRITE,
    )
    sky: str = option(
        "constant",
        "the sky: constant (the uniform sky of --sky-radiance) or sunsky (Mitsuba's physical sun and "
        "sky, its sun along --sun-elevation/--sun-azimuth; fogref/render/sunsky.py)",
        check=Choice(("constant", "sunsky")),
        group=LIGHT,
        api=WRITE,
    )
    turbidity: float = option(
        3.0, "the sunsky's atmospheric turbidity, [1, 10]", check=Number(), group=LIGHT, api=WRITE
    )
    sun_angular_diameter: float | None = option(
        None,
        "the sun's angular diameter [deg], [0, 10]: 0 a delta, 0.53 the real sun (default: none declared)",
        check=Number(),
        group=LIGHT,
        api=WRITE,
    )
    camera_origin: tuple = option(
        (0.0, 2.0, 0.0), "camera position [m]", check=Text(), metavar="X,Y,Z", group=CAMERA, api=WRITE
    )
    camera_target: tuple = option(
        (0.15, 2.35, 1.0),
        "a point the camera looks at [m]",
        check=Text(),
        metavar="X,Y,Z",
        group=CAMERA,
        api=WRITE,
    )
    fov: float = option(
        70.0, f"horizontal field of view, {_range(RANGES, 'fov')}", check=Number(), group=CAMERA, api=WRITE
    )
    res: int = option(320, f"image width, {_range(RANGES, 'res')}", check=Integer(), group=CAMERA, api=WRITE)
    resy: int = option(
        180, f"image height, {_range(RANGES, 'resy')}", check=Integer(), group=CAMERA, api=WRITE
    )
    ground_reflectance: str | None = option(
        None,
        f"diffuse reflectance of the ground plane, grey or RGB, {_range(RANGES, 'reflectance')} "
        "(plane: the reflectance default; with a mesh: its own BSDF unless equal to the mesh's)",
        check=Text(),
        metavar="R[,G,B]",
        group=GEOMETRY,
        api=WRITE,
        default_text="0.2",
    )
    mesh_reflectance: str | None = option(
        None,
        f"diffuse reflectance of the mesh, grey or RGB, {_range(RANGES, 'reflectance')} "
        "(the reflectance default of a mesh scene)",
        check=Text(),
        metavar="R[,G,B]",
        group=GEOMETRY,
        api=WRITE,
        default_text="0.2",
    )


#: the Unreal editor values with no physical counterpart: accepted, written as a note
_IGNORED_FIELDS = [
    (
        _dest(opt),
        float | None if kind == "number" else str | None,
        option(
            None,
            f"{key}: no physical counterpart, ignored with a note ({why}); "
            f"{_range(UNREAL_IGNORED_RANGES, key)}"
            + ("; linear RGB, as Unreal's FLinearColor" if kind == "rgb" else ""),
            flag=opt,
            check=Number() if kind == "number" else Text(),
            metavar="R,G,B" if kind == "rgb" else None,
            group=UE,
        ),
    )
    for key, (opt, kind, why) in UNREAL_IGNORED.items()
]
Options = make_dataclass("Options", _IGNORED_FIELDS, bases=(_Options,))
Options.__doc__ = "The options of ``fogref scene`` (those of :func:`fogref.scene.writer.write_scene`)."
Options.__module__ = __name__


def run(a, given=frozenset()) -> int:
    """Write the scene; print its path (notes on stderr)."""
    phys = {k: getattr(a, k) for k in PHYSICAL if getattr(a, k) is not None}
    ue: dict = {}
    for key, opt in [*UNREAL_MAPPED.items(), *((k, opt) for k, (opt, _, _) in UNREAL_IGNORED.items())]:
        v = getattr(a, _dest(opt))
        if v is not None and key.startswith("SecondFogData."):
            ue.setdefault("SecondFogData", {})[key.split(".", 1)[1]] = v
        elif v is not None:
            ue[key] = v
    if phys and ue:
        p_opts = ", ".join(PHYSICAL[k].option for k in phys)
        u_opts = ", ".join(sorted(_ue_option(k) for k in flat_unreal(ue)))
        raise UsageError(
            f"{SOURCE}: give the fog either in physical units or as Unreal editor values, not both "
            f"(got {p_opts} and {u_opts})"
        )
    pt_given = {opt: getattr(a, _dest(opt)) for opt in PT_OPTIONS if getattr(a, _dest(opt)) is not None}
    pt = None
    if a.ue_pathtracer or a.ue_exact:
        pt = _pathtracer_settings(pt_given, phys, a)
    elif pt_given:
        raise UsageError(f"{SOURCE}: {', '.join(pt_given)}: only with --ue-pathtracer or --ue-exact")
    albedo, g, phase, fog_notes = a.albedo, a.g, None, ()
    if a.visibility is not None or a.droplets is not None:
        albedo, g, phase, fog_notes = _droplet_fog(a, phys, ue)
    elif a.phase is not None or a.grey_extinction or "contrast" in given:
        raise UsageError(
            f"{SOURCE}: --phase, --contrast and --grey-extinction need --visibility or --droplets"
        )
    _refuse_sky_options(a, given)
    sky = a.sky_radiance
    if isinstance(sky, str) and sky.strip().lower() == "none":
        sky = None

    def note(n: str) -> None:
        if pt is not None and n.startswith("Unreal has no albedo"):
            return  # the path-traced fog has VolumetricFogAlbedo and its g
        print(f"fogref scene: note: {n}", file=sys.stderr)

    write_args = {**api_arguments(a, WRITE), "albedo": albedo, "g": g, "sky_radiance": sky}
    r = write_scene(
        a.out,
        fog=phys if not ue else None,
        unreal=ue or None,
        phase=phase,
        notes=fog_notes,
        on_note=note,
        **write_args,
    )
    if pt is not None:
        uf = UE4FogParams(**{k: v for k, v in ue.items() if k not in UNREAL_IGNORED})
        exact = exact_fog_params(uf, pt) if a.ue_exact else None
        rewrite_scene(r.path, r.path, uf, pt, params=exact)  # the cylinder follows $camera_origin
        dropped = sorted(k for k in ue if k in DROPPED)
        if dropped:
            note(f"Unreal's path tracer does not use {', '.join(dropped)} (raster-only values)")
    print(r.path)
    return 0


def _droplet_fog(a, phys: dict, ue: dict) -> tuple:
    """``phys['sigma_t']`` set from --visibility/--droplets (refused beside --sigma-t, Unreal
    values, and --albedo/--g with droplets); returns (albedo, g, phase, notes)."""
    clash = ["--sigma-t"] if "sigma_t" in phys else []
    clash += sorted(_ue_option(k) for k in flat_unreal(ue))
    clash += [f"--{k.replace('_', '-')}" for k in ("ue_pathtracer", "ue_exact") if getattr(a, k)]
    if a.droplets is not None:
        clash += [opt for opt, v in (("--albedo", a.albedo), ("--g", a.g)) if v is not None]
    if clash:
        raise UsageError(
            f"{SOURCE}: --visibility/--droplets set the fog's extinction"
            + (", albedo and phase" if a.droplets else "")
            + f"; not with {', '.join(clash)}"
        )
    df = droplet_fog(
        a.visibility,
        a.droplets,
        contrast=a.contrast,
        phase=a.phase,
        grey=a.grey_extinction,
        g=0.6 if a.g is None else a.g,
        albedo=0.9 if a.albedo is None else a.albedo,
        src=SOURCE,
    )
    phys["sigma_t"] = list(df.sigma_t)
    return list(df.albedo), df.g, df.phase, df.notes


def _refuse_sky_options(a, given) -> None:
    """UsageError for a light option the chosen ``--sky`` does not use (refused, not ignored)."""
    if a.sky == "constant" and "turbidity" in given:
        raise UsageError(f"{SOURCE}: --turbidity applies only with --sky sunsky (the constant sky has none)")
    if a.sky == "sunsky":
        unused = [f"--{n.replace('_', '-')}" for n in ("sky_radiance", "sun_irradiance") if n in given]
        if unused:
            raise UsageError(
                f"{SOURCE}: {', '.join(unused)} does not apply with --sky sunsky (Mitsuba's sunsky gives "
                "the sun's and the sky's radiance from --turbidity and the sun's elevation)"
            )


def _pathtracer_settings(given: dict, phys: dict, a) -> object:
    """The checked path-traced fog settings of ``--ue-*`` (refused beside physical fog, --albedo, --g)."""
    clash = [PHYSICAL[k].option for k in phys]
    clash += [opt for opt, v in (("--albedo", a.albedo), ("--g", a.g)) if v is not None]
    if clash:
        raise UsageError(
            f"{SOURCE}: --ue-pathtracer and --ue-exact take the fog as Unreal values (its albedo and g are "
            "--ue-volumetric-fog-albedo and --ue-volumetric-fog-scattering-distribution), "
            f"not {', '.join(clash)}"
        )
    return validated_settings(
        SOURCE,
        dict((v, k) for k, v in PT_OPTIONS.items()),
        **{PT_OPTIONS[opt]: v for opt, v in given.items()},
    )

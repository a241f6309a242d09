"""A tiny fogref scene that loads an OBJ mesh, an envmap EXR and a bitmap texture (PNG), for the
tests of the files a scene loads (tests/test_render_inputs.py, tests/test_checkpoint_atomic.py)."""

from pathlib import Path

import numpy as np

#: 8x6 pixels: 4 spp in passes of 1 spp when MAX_LANES is 48 (see ``one_spp_passes``).
RES = {"res": 8, "resy": 6}

SCENE = """<scene version="3.0.0">
    <default name="res" value="8"/>
    <default name="resy" value="6"/>
    <default name="mesh" value="box.obj"/>
    <default name="sky" value="sky.exr"/>
    <integrator type="fogpath"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="70"/>
        <string name="fov_axis" value="x"/>
        <transform name="to_world"><lookat origin="0, 2, 0" target="0, 2.3, 1" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="$res"/><integer name="height" value="$resy"/><rfilter type="box"/>
        </film>
        <medium type="heightfog" name="medium">
            <string name="profile" value="exponential"/>
            <float name="sigma_t" value="0.02"/><float name="albedo" value="0.9"/>
            <float name="g" value="0.6"/>
            <float name="falloff" value="0.0138629"/><float name="density" value="1"/>
            <float name="height" value="0"/>
        </medium>
    </sensor>
    <emitter type="directional" id="sun">
        <vector name="direction" value="0.3, -0.4, 1"/><rgb name="irradiance" value="3.2, 2.9, 2.4"/>
    </emitter>
    <emitter type="envmap" id="sky"><string name="filename" value="$sky"/></emitter>
    <bsdf type="diffuse" id="ground">
        <texture type="bitmap" name="reflectance"><string name="filename" value="tex.png"/></texture>
    </bsdf>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="60"/></transform>
        <ref id="ground"/>
    </shape>
    <shape type="obj">
        <string name="filename" value="$mesh"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.25, 0.23, 0.20"/></bsdf>
    </shape>
</scene>
"""


def write_obj(path: Path, dx: float = 0.0) -> None:
    """A 4 m x 4 m wall at z = 10 m in front of the camera, moved ``dx`` metres along x."""
    v = [(-2, 0, 10), (2, 0, 10), (2, 4, 10), (-2, 4, 10)]
    text = "".join(f"v {x + dx} {y} {z}\n" for x, y, z in v) + "f 1 2 3\nf 1 3 4\n"
    Path(path).write_text(text)


def write_envmap(mi, path: Path, level: float = 0.3) -> None:
    """A 16x8 latitude-longitude sky, bluish, of radiance ``level`` (EXR)."""
    img = np.empty((8, 16, 3), np.float32)
    img[...] = np.array([0.7, 0.85, 1.0], np.float32) * level
    img[:4] *= 1.5  # the upper half brighter
    mi.Bitmap(img).write(str(path))


def write_texture(mi, path: Path, grey: int = 90) -> None:
    """A 4x4 checker PNG (sRGB 8 bit) around ``grey``."""
    img = np.full((4, 4, 3), grey, np.uint8)
    img[::2, ::2] = min(255, grey + 60)
    mi.Bitmap(img, mi.Bitmap.PixelFormat.RGB).write(str(path))


def make(mi, folder: Path) -> Path:
    """The scene ``s.xml`` and its files ``box.obj``, ``sky.exr``, ``tex.png`` in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    write_obj(folder / "box.obj")
    write_envmap(mi, folder / "sky.exr")
    write_texture(mi, folder / "tex.png")
    scene = folder / "s.xml"
    scene.write_text(SCENE)
    return scene


def one_spp_passes(monkeypatch) -> None:
    """Passes of 1 spp at 8x6 pixels (MAX_LANES = 48), so that a render can stop between passes."""
    import fogref_plugins.passes as passes

    monkeypatch.setattr(passes, "MAX_LANES", {"llvm": 48, "cuda": 48})

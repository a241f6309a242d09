"""fogref as a plain ``pip install`` sees it: the wheel, installed into a fresh virtual environment
outside the checkout, has its scenes, and the CI example of the README (tests/test_byo_example.py)
passes there.  The dependencies are this environment's (a ``.pth`` file), so nothing but the build
backend pip already holds is fetched; the wheel itself is installed with ``--no-index``."""

import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(*args, cwd, env=None):
    r = subprocess.run([str(a) for a in args], cwd=cwd, capture_output=True, text=True, env=env, timeout=1800)
    assert r.returncode == 0, f"{' '.join(map(str, args))}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    return r.stdout


@pytest.mark.render
def test_the_wheel_stands_alone_and_runs_the_readme_ci_example(tmp_path):
    wheels = tmp_path / "wheels"
    _run(sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", wheels, ROOT, cwd=tmp_path)
    (wheel,) = wheels.glob("fogref-*.whl")
    venv = tmp_path / "venv"
    _run(sys.executable, "-m", "venv", "--without-pip", venv, cwd=tmp_path)
    python = venv / "bin" / "python"
    site = Path(
        _run(python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])", cwd=tmp_path).strip()
    )
    (site / "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    _run(
        sys.executable,
        "-m",
        "pip",
        "--python",
        python,
        "install",
        "-q",
        "--no-deps",
        "--no-index",
        wheel,
        cwd=tmp_path,
    )

    project = tmp_path / "studio"
    project.mkdir()
    where = _run(python, "-c", "import fogref; print(fogref.scene_path('valley'))", cwd=project).strip()
    assert Path(where).is_file() and Path(where).is_relative_to(venv), where
    _run(venv / "bin" / "fogref", "scene", "--out", "scenes/studio.xml", "--geometry", "valley", cwd=project)
    assert "<shape" in (project / "scenes" / "studio.xml").read_text()

    text = (ROOT / "tests" / "test_byo_example.py").read_text()
    example = text.split("# --- example start ---\n")[1].split("# --- example end ---")[0]
    (project / "test_ci.py").write_text(example)
    env = {**os.environ, "FOGREF_CACHE": str(tmp_path / "cache")}
    out = _run(python, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_ci.py", cwd=project, env=env)
    assert "1 passed" in out

import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
SCENES = ROOT / "scenes"


@pytest.fixture(scope="session")
def mitsuba():
    """Mitsuba with fogref's plugins (llvm_ad_rgb)."""
    if os.environ.get("FOGREF_NO_MITSUBA"):
        if os.environ.get("CI"):
            pytest.fail("FOGREF_NO_MITSUBA is set in CI: the render tests would not run")
        pytest.skip("FOGREF_NO_MITSUBA is set")
    import fogref

    fogref.set_variant("llvm_ad_rgb")
    import mitsuba as mi

    return mi

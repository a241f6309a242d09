import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
SCENES = ROOT / "scenes"


@pytest.fixture(scope="session")
def mitsuba():
    """Mitsuba set up for fogref (llvm_ad_rgb, plugins registered): ``import fogref`` alone does not."""
    import fogref

    fogref.set_variant("llvm_ad_rgb")
    import mitsuba as mi

    return mi

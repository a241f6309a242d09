"""A full disk while the truth is written: one line naming the file, the older output kept.

OpenEXR reports a failed write (ENOSPC) as a RuntimeError, not an OSError; before this test
it reached the user as a traceback. The write is made to fail the way OpenEXR fails on a full
disk (its own message), so the test needs no small file system.
"""

import numpy as np
import OpenEXR
import pytest

from fogref.cli import main
from fogref.exrio import read_exr, write_exr


def _fail_like_a_full_disk(monkeypatch):
    def write(self, path):
        open(path, "wb").write(b"\0" * 16)  # a partial temporary, as a real full disk leaves one
        raise RuntimeError(f'Failed to write pixel data to image file "{path}". No space left on device.')

    monkeypatch.setattr(OpenEXR.File, "write", write)


def test_write_exr_on_a_full_disk_keeps_the_older_file(tmp_path, monkeypatch):
    out = tmp_path / "t.exr"
    write_exr(out, {"R": np.ones((2, 3))}, {"fogref.note": "older"})
    _fail_like_a_full_disk(monkeypatch)
    with pytest.raises(OSError, match="No space left on device.*an older file there is kept") as e:
        write_exr(out, {"R": np.zeros((2, 3))})
    assert e.value.filename == str(out)
    monkeypatch.undo()
    chans, attrs = read_exr(out)
    assert attrs["fogref.note"] == "older" and float(chans["R"].max()) == 1.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.exr"]  # no temporary left behind


@pytest.mark.render
def test_render_on_a_full_disk_is_one_line(tmp_path, monkeypatch, capsys):
    out = tmp_path / "v.exr"
    _fail_like_a_full_disk(monkeypatch)
    args = ["render", "scenes/valley.xml", "--set", "res=8", "--set", "resy=6", "--spp", "1", "--quiet"]
    rc = main([*args, "--no-png", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "Traceback" not in err and len(err.splitlines()) == 1
    assert err.startswith(f"fogref: error: {out}: No space left on device")

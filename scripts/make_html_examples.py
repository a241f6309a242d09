"""Write the example HTML reports from the committed data, and their screenshots.

    .venv/bin/python scripts/make_html_examples.py [--truth out/valley.exr]

reports/unreal_study/report.html (from summary.json, budget.json and compare/: the truth,
out/valley.exr, is not committed, so the viewer shows the compared parts, with the noise of
the error as their standard error) and reports/sweeps/unreal_sun_falloff_g/report.html (from
results.csv, with plots/ redrawn from it), each with report.png (the page in headless Chromium) beside it.
No study or sweep is re-run.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from browser_util import console_errors, find_browser, load, screenshot, start  # noqa: E402

from fogref.html.reports import write_study_html, write_sweep_html  # noqa: E402


def replot_sweep(folder: Path) -> None:
    """The sweep's plots again from its committed table (fogref.study.sweep.table.plot_table)."""
    import pandas as pd

    from fogref.study.sweep import load_sweep
    from fogref.study.sweep.table import plot_table

    spec = load_sweep(folder / "SWEEP.toml")
    plot_table(pd.read_csv(folder / "results.csv"), spec, folder / "plots")


def main(argv=None) -> int:
    """``[--truth EXR]``: the study's truth, when at hand (the viewer then shows its every part)."""
    argv = sys.argv[1:] if argv is None else argv
    truth = None
    if argv[:1] == ["--truth"]:
        from fogref.gbuffer import load_truth

        truth = load_truth(argv[1])
    sweep = ROOT / "reports/sweeps/unreal_sun_falloff_g"
    replot_sweep(sweep)
    pages = [write_study_html(ROOT / "reports/unreal_study", truth), write_sweep_html(sweep)]
    for p in pages:
        print(f"{p.relative_to(ROOT)}: {p.stat().st_size / 1e6:.2f} MB")
    *_, why = find_browser()
    if why:
        print(f"no screenshots: {why}")
        return 0
    drv = start()
    try:
        for p in pages:
            load(drv, p)
            errors = console_errors(drv)
            if errors:
                raise SystemExit(f"{p}: console errors {errors}")
            if drv.find_elements("id", "fr-canvas"):  # show the viewer at work: a swipe truth | error
                drv.execute_script(
                    "var s=function(id,v){var e=document.getElementById(id);e.value=v;"
                    "e.dispatchEvent(new Event('change'));};s('fr-b','error');s('fr-mode','swipe');"
                    "window.fogrefViewer.readout(200, 150);"
                )
            shot = screenshot(drv, p.with_suffix(".png"))
            print(f"{shot.relative_to(ROOT)}")
    finally:
        drv.quit()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

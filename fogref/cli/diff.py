"""``fogref diff A B``: do two renders or two images differ beyond noise?  No reference needed.

Two truths: every part's difference against both truths' per-pixel noise
(:func:`fogref.compare.diff.diff`): ``equal within noise`` or ``differ``.  Two images: equal
when ``max |B - A| <= --tolerance``.  Exit codes: 0 equal, 1 differ, 2 usage or input error.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from fogref.atomic import check_output_file, refuse_overwriting_inputs, write_text_atomic
from fogref.cli.checks import Choice, Number, PathArg
from fogref.cli.spec import option
from fogref.compare.diff import diff, load_side
from fogref.compare.foreign import ENCODINGS
from fogref.html.reports import write_diff_html

NAME = "diff"
HELP = "do two truths (or images) differ beyond noise? exit 0 equal, 1 differ, 2 error"
DESCRIPTION = (
    "Compare two ground truths (two fogref versions, seeds or machines) with both truths' per-pixel "
    "noise, or a truth and an image with the truth's, or two images exactly (--tolerance): bias and "
    "debiased RMSE of T, inscatter and final per region, Bonferroni-corrected intervals; the verdict is "
    "'equal within noise' or 'differ'."
)
EPILOG = "exit codes: 0 equal (within noise), 1 differ, 2 usage or input error"


@dataclass
class Options:
    a: str = option(
        help="first truth EXR or image (.exr, .png, .hdr)",
        positional=True,
        check=PathArg(must_exist=True),
        metavar="A",
    )
    b: str = option(
        help="second truth EXR or image", positional=True, check=PathArg(must_exist=True), metavar="B"
    )
    confidence: float = option(
        0.99,
        "level of the whole verdict (Bonferroni over the rows)",
        check=Number(0.0, 1.0, lo_open=True, hi_open=True),
        metavar="C",
        api="fogref.compare.diff:diff",
    )
    tolerance: float = option(
        0.0,
        "two images: largest |B - A| still equal [the images' units]",
        check=Number(0.0),
        metavar="X",
        api="fogref.compare.diff:diff",
    )
    encoding: str = option(
        "auto",
        "how images (not truths) are encoded (auto: 8-bit PNG is sRGB)",
        check=Choice(ENCODINGS),
    )
    json: str | None = option(
        None,
        "write the verdict, the rows and the exit code as JSON",
        check=PathArg(role="output"),
        metavar="FILE",
    )
    out: str | None = option(
        None,
        "also write report.html (the viewer: A as the truth, B as the candidate)",
        check=PathArg(),
        metavar="DIR",
    )


def run(o: Options, given=frozenset()) -> int:
    """Print the diff and return its exit code."""
    if o.out:
        page = Path(o.out) / "report.html"
        check_output_file(page, "fogref diff: --out")
        refuse_overwriting_inputs([(page, "report")], [(o.a, "A"), (o.b, "B")], "fogref diff: --out")
    a, b = load_side(o.a, o.encoding), load_side(o.b, o.encoding)
    result = diff(a, b, confidence=o.confidence, tolerance=o.tolerance, names=(o.a, o.b))
    print("\n".join(result.lines()))
    if o.json:
        write_text_atomic(o.json, json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n")
    if o.out:
        print(f"html: {write_diff_html(Path(o.out), result, a, b)}")
    print(f"exit code {result.code} ({result.verdict})")
    return result.code

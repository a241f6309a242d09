"""``fogref compare`` as a CI gate: tolerance parsing, exit codes, ``--json`` and ``--junit`` files.

The verdict is :func:`fogref.compare.check.check`'s (the checker of the pytest
plugin's ``assert_fog_matches``): ``CheckResult.verdict``.  Exit codes:

====  ==============================================================
code  meaning
====  ==============================================================
0     pass: every row with a tolerance passes
1     fail: at least one row fails
2     usage or input error (argparse, or a one-line ``fogref: error:``)
3     inconclusive: nothing fails, but at least one interval straddles
      its tolerance (the truth is too noisy or too small to decide)
====  ==============================================================

The options themselves are declared in :mod:`fogref.cli.compare`.
``--inconclusive fail`` / ``pass`` turn an inconclusive verdict into exit 1 / 0.

JUnit XML (``--junit``): one ``testcase`` per row that has a tolerance
(``classname`` ``fogref.<part>.<region>``, ``name`` the metric), a ``failure``
element (``type="fail"``) for a failed row; an inconclusive row gets a ``failure``
element with ``type="inconclusive"`` (it gates, as exit code 3 does), or a
``skipped`` element under ``--inconclusive pass``; a row without pixels
(``empty``) is ``skipped``.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

from fogref.atomic import write_text_atomic
from fogref.errors import FogrefError

#: Exit code of each overall verdict (2 is a usage or input error).
EXIT_CODES: dict[str, int] = {"pass": 0, "fail": 1, "inconclusive": 3}


def parse_tolerances(items) -> dict:
    """``--tolerance PART[/REGION][:METRIC]=VALUE`` options as check()'s ``tolerances`` dict.

    METRIC defaults to ``rel_rmse``; VALUE is a number (finite, >= 0) or ``none`` (only
    report the metric).  A row given twice is refused (FogrefError), as every repeated
    option is.  Names are not checked here: :func:`fogref.compare.check.check` rejects
    unknown parts, regions and metrics.

    >>> parse_tolerances(["inscatter/sky=0.05", "T:rel_bias=0.001", "T:rmse=none"])
    {'inscatter/sky': {'rel_rmse': 0.05}, 'T': {'rel_bias': 0.001, 'rmse': None}}
    >>> parse_tolerances(["foo"])
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: --tolerance foo: expected PART[/REGION][:METRIC]=VALUE, ...
    """
    out: dict = {}
    for item in items or []:
        key, eq, value = str(item).partition("=")
        where, _, metric = key.strip().partition(":")
        if not eq or not where or (":" in key and not metric):
            raise FogrefError(
                f"--tolerance {item}: expected PART[/REGION][:METRIC]=VALUE, "
                "e.g. inscatter/sky=0.05 or T:rel_bias=0.001"
            )
        value = value.strip()
        if value.lower() == "none":
            tol = None
        else:
            try:
                tol = float(value)
            except ValueError:
                tol = math.nan
            if not (math.isfinite(tol) and tol >= 0):
                raise FogrefError(
                    f"--tolerance {item}: value '{value}' must be a finite number >= 0 "
                    "(relative metrics: 0.05 is 5 %) or 'none'"
                )
        row, metric = out.setdefault(where.strip(), {}), metric.strip() or "rel_rmse"
        if metric in row:
            raise FogrefError(f"--tolerance {item}: {where.strip()}:{metric} is given twice; give each once")
        row[metric] = tol
    return out


def parse_distance_bands(text: str) -> tuple[float, ...]:
    """``--distance-bands 100,1000`` [m] as a tuple (``none``: no distance regions).

    >>> parse_distance_bands("100,1000"), parse_distance_bands("none")
    ((100.0, 1000.0), ())
    """
    if text.strip().lower() in ("none", ""):
        return ()
    try:
        edges = tuple(float(x) for x in text.split(","))
    except ValueError:
        edges = (math.nan,)
    if not all(math.isfinite(e) and e > 0 for e in edges) or any(b <= a for a, b in zip(edges, edges[1:])):
        raise FogrefError(
            f"--distance-bands {text}: expected increasing distances [m] > 0 separated by "
            "commas (e.g. 100,1000) or 'none'"
        )
    return edges


def exit_code(verdict: str, inconclusive: str | None = None) -> int:
    """The exit code of an overall verdict; ``inconclusive`` (``"fail"``/``"pass"``) remaps it.

    >>> exit_code("pass"), exit_code("fail"), exit_code("inconclusive"), exit_code("inconclusive", "pass")
    (0, 1, 3, 0)
    """
    if verdict == "inconclusive" and inconclusive is not None:
        return EXIT_CODES[inconclusive]
    return EXIT_CODES[verdict]


def gate_dict(result, code: int, **extra) -> dict:
    """JSON-ready: every row (estimate, interval, tolerance, verdict), the verdict and the exit code."""
    return {**result.to_dict(), "exit_code": code, **extra}


def write_json(path, result, code: int, **extra) -> Path:
    """Write :func:`gate_dict` to ``path`` atomically (no NaN)."""
    text = json.dumps(gate_dict(result, code, **extra), indent=2, allow_nan=False)
    return write_text_atomic(path, text + "\n")


def junit_xml(result, inconclusive: str | None = None) -> str:
    """JUnit XML of the rows that have a tolerance (see the module's docstring for the mapping)."""
    rows = [r for r in result.rows if r.tolerance is not None]
    suite = ET.Element("testsuite", name="fogref compare", tests=str(len(rows)))
    counts = {"failures": 0, "skipped": 0}
    for r in rows:
        case = ET.SubElement(suite, "testcase", classname=f"fogref.{r.part}.{r.region}", name=r.metric)
        if r.verdict == "fail" or (r.verdict == "inconclusive" and inconclusive != "pass"):
            ET.SubElement(case, "failure", type=r.verdict, message=r.describe())
            counts["failures"] += 1
        elif r.verdict in ("inconclusive", "empty"):
            ET.SubElement(case, "skipped", message=r.describe())
            counts["skipped"] += 1
    suite.set("failures", str(counts["failures"]))
    suite.set("skipped", str(counts["skipped"]))
    ET.SubElement(suite, "system-out").text = result.summary()
    return ET.tostring(suite, encoding="unicode", xml_declaration=True) + "\n"


def finish(args, result, **extra) -> int:
    """Write ``--json``/``--junit``, print the verdict and return the exit code.

    ``args``: anything with ``inconclusive``, ``json`` and ``junit`` (``fogref compare``'s options,
    :class:`fogref.cli.compare.Options`)."""
    code = exit_code(result.verdict, args.inconclusive)
    if args.json:
        write_json(args.json, result, code, **extra)
    if args.junit:
        write_text_atomic(args.junit, junit_xml(result, args.inconclusive))
    print(result.summary())
    print(f"exit code {code} ({result.verdict})")
    return code

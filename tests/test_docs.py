"""The README says what the code does: its channel table is the schema's, its CI
example is the one the suite runs, and its commands name real subcommands."""

import re
from pathlib import Path

from fogref import gbuffer
from fogref.cli import build_parser

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()


def test_readme_channel_table_is_the_schema():
    assert gbuffer.readme_table() in README


def test_readme_ci_example_is_the_one_the_suite_runs():
    text = (Path(__file__).parent / "test_byo_example.py").read_text()
    example = text.split("# --- example start ---\n")[1].split("# --- example end ---")[0].strip()
    assert example in README


def test_readme_commands_parse():
    parser = build_parser()
    for line in re.findall(r"^\.venv/bin/fogref (.+?)(?:\s+#.*)?$", README, flags=re.M):
        args = line.split()
        if args[0] == "compare" and "--image" in args:
            continue  # names files the reader does not have
        parser.parse_args(args)

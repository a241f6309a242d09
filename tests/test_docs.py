"""The docs say what the code does: docs/schema.md's channel table is the schema's, the
README's CI example is the one the suite runs, and its commands name real subcommands."""

import re
from pathlib import Path

from fogref import gbuffer
from fogref.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
SCHEMA_DOC = (ROOT / "docs" / "schema.md").read_text()


def test_schema_doc_channel_table_is_the_schema():
    assert gbuffer.schema_table() in SCHEMA_DOC


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

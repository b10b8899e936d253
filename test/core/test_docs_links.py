"""The documentation a new user follows leads somewhere: every relative link of README.md, docs/*.md
and the plants' README.md resolves, and every ``--help`` text (each ``cablelab`` verb, the demo,
the node executables) names only files that are in the repository."""
from __future__ import annotations

import contextlib
import io
import re
import shutil
import subprocess
import sys

import pytest

from robust_helpers import REPO

DOCS = sorted([REPO / "README.md", *(REPO / "docs").glob("*.md"),
               *(REPO / "src" / "cablelab" / "cablelab" / "plants").glob("*/README.md")])
#: a markdown link or image: [text](target) / ![alt](target)
LINK = re.compile(r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
#: a file a help text points to: a path ending in a documentation or source suffix
FILE_REF = re.compile(r"(?<![\w/.-])([\w./-]+\.(?:md|py|yaml|yml|txt|toml|cfg))(?![\w/-])")


def relative_links(path):
    """``[(target, resolved path)]`` of the relative links of one markdown file (anchors dropped)."""
    out = []
    for target in LINK.findall(path.read_text(encoding="utf-8")):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue                                   # http:, mailto:, in-page anchors
        out.append((target, (path.parent / target.split("#")[0]).resolve()))
    return out


def test_the_doc_set_is_found():
    names = {p.relative_to(REPO).as_posix() for p in DOCS}
    assert {"README.md", "docs/interface.md", "src/cablelab/cablelab/plants/cdpr/README.md"} <= names


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.relative_to(REPO).as_posix())
def test_every_relative_link_resolves(doc):
    broken = [t for t, p in relative_links(doc) if not p.exists()]
    assert not broken, f"{doc.relative_to(REPO)}: broken links {broken}"


def test_link_checker_finds_a_broken_link(tmp_path):
    md = tmp_path / "x.md"
    (tmp_path / "there.md").write_text("")
    md.write_text("[ok](there.md) [gone](cdpr.md#topics) [web](https://example.org) [a](#top)")
    assert [t for t, p in relative_links(md) if not p.exists()] == ["cdpr.md#topics"]


def _verb_helps() -> dict[str, str]:
    from cablelab.cli import build_parser

    parser = build_parser()
    helps = {"cablelab": parser.format_help()}
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    for verb, p in sub.choices.items():
        helps[f"cablelab {verb}"] = p.format_help()
    return helps


def _demo_help() -> str:
    from cablelab import demo

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), pytest.raises(SystemExit):
        demo.main(["--help"])
    return buf.getvalue()


def file_refs(text: str) -> list[str]:
    """Files a help text names (argparse may wrap a line inside a path: lines are joined); a
    metavar placeholder (``FILE.yaml``, ``DIR/x.txt``: an upper-case component) names none."""
    return [f for f in FILE_REF.findall(" ".join(text.split()))
            if not any(re.fullmatch(r"[A-Z][A-Z0-9_]*", part.split(".")[0]) for part in f.split("/"))]


def missing_refs(text: str) -> list[str]:
    """What a help text points to that the repository lacks: files, and the project contract's
    sections (CONTRACT.md is not shipped: help must point to docs/interface.md instead)."""
    out = [f for f in file_refs(text) if not any((base / f).exists() for base in (
        REPO, REPO / "docs", REPO / "src" / "cablelab"))]
    out += re.findall(r"CONTRACT(?:\.md)?(?: sec(?:tion|\.) \d+)?", text)
    return out


def test_help_reference_checker_catches_the_old_pointer():
    assert missing_refs("effect ids (ids of CONTRACT section 4)") == ["CONTRACT section 4"]
    assert missing_refs("see docs/nowhere.md and docs/interface.md") == ["docs/nowhere.md"]
    assert missing_refs("--params-file FILE.yaml, DIR/notes.txt") == []


def test_every_verb_help_names_only_files_in_the_repository():
    helps = _verb_helps()
    helps["./run demo"] = _demo_help()
    assert len(helps) >= 12 and "docs/interface.md" in helps["cablelab diagnose"]
    bad = {name: missing_refs(text) for name, text in helps.items() if missing_refs(text)}
    assert not bad, bad


def _console_scripts() -> list[str]:
    """Every executable the repository's packages install (their setup.cfg console_scripts)."""
    import configparser

    names = []
    for cfg in sorted((REPO / "src").glob("*/setup.cfg")):
        parser = configparser.ConfigParser()
        parser.read(cfg)
        spec = parser.get("options.entry_points", "console_scripts", fallback="")
        names += [line.split("=")[0].strip() for line in spec.splitlines() if "=" in line]
    return names


def test_the_executables_are_found():
    assert {"cable_sim_node", "payload_estimator", "pd_feedforward"} <= set(_console_scripts())


@pytest.mark.parametrize("exe", _console_scripts())
def test_node_help_names_only_files_in_the_repository(exe):
    path = shutil.which(exe, path=str(REPO / ".venv" / "bin")) or shutil.which(exe)
    if path is None:
        pytest.skip(f"{exe} is not installed")
    res = subprocess.run([sys.executable, path, "--help"], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0 and "usage" in res.stdout.lower(), res.stderr
    assert not missing_refs(res.stdout), missing_refs(res.stdout)


def test_interface_lists_every_verb_the_cli_has():
    """docs/interface.md section 4 has a row for each `cablelab` verb and calls none missing."""
    from cablelab.cli import build_parser

    text = (REPO / "docs" / "interface.md").read_text()
    section = text[text.index("## 4. Command line"):]
    rows = set(re.findall(r"^\| `([a-z][a-z-]*)[ `]", section, flags=re.M))
    sub = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    assert set(sub.choices) <= rows, set(sub.choices) - rows
    assert "not part of this repository" not in section

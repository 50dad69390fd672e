"""The project's own documents: tables that render, links that resolve, and a contract (docs/cli.md) that names
every command-line option and every summary JSON key the code produces."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from convexguid.cli import main
from convexguid.families import FAMILIES
from convexguid.scp.problem import ProgramSize
from convexguid.solution import Solution
from convexguid.verification import ConstraintCheck, Verification

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
CONTRACT = ROOT / "docs" / "cli.md"


def _is_row(line: str) -> bool:
    return line.lstrip().startswith("|")


def _is_separator(line: str) -> bool:
    return re.fullmatch(r"\s*\|?(\s*:?-+:?\s*\|)+\s*:?-*:?\s*", line) is not None


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda p: p.name)
def test_tables_are_not_cut_by_blank_lines(document):
    """A blank line ends a markdown table; rows after it (without a header of their own) render as text."""
    lines = document.read_text().splitlines()
    for i in range(1, len(lines) - 1):
        if lines[i].strip() == "" and _is_row(lines[i - 1]) and _is_row(lines[i + 1]):
            follows = lines[i + 2] if i + 2 < len(lines) else ""
            assert _is_separator(follows), f"{document.name} line {i + 1}: blank line inside a table"


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda p: p.name)
def test_relative_links_and_named_documents_exist(document):
    text = document.read_text()
    targets = re.findall(r"\]\(([^)#\s]+)[^)]*\)", text) + re.findall(r"`((?:docs|validation)/[\w./-]+\.md)`", text)
    for target in targets:
        if "://" in target or "*" in target or target.endswith(".timings.md"):
            continue
        assert (document.parent / target).exists() or (ROOT / target).exists(), f"{document.name}: {target}"


def test_no_reference_to_a_document_outside_the_repository():
    outside = "design" + ".md"  # the old contract, never part of the repository
    sources = [*DOCUMENTS, *(ROOT / "convexguid").rglob("*.py"), *(ROOT / "problems").glob("*.yaml"),
               *(ROOT / "tests").glob("*.py")]
    named = [str(p.relative_to(ROOT)) for p in sources if outside in p.read_text()]
    assert not named


@pytest.mark.parametrize("command", ["solve", "simulate", "validate", "bench", "campaign"])
def test_the_contract_names_every_option(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    options = set(re.findall(r"(--[a-z][a-z-]+)", capsys.readouterr().out)) - {"--help"}
    assert options
    contract = CONTRACT.read_text()
    assert [o for o in sorted(options) if o not in contract] == []


def test_the_contract_names_every_summary_key():
    check = ConstraintCheck("torque_Nm", 0.5, 1.0, "max")
    verification = Verification(grid_points=10, checks=(check,), final_state_error=0.0,
                                final_errors={"final_attitude_error_rad": 0.0}, passed=True)
    summary = Solution(problem="p", family="flat_attitude", method="scp", status="converged", objective=0.0,
                       iterations=1, size=ProgramSize(1, 0, 0), wall_time_s=0.0, solver="auto",
                       verification=verification).summary()
    keys = set(summary) | (set(summary["verification"]) - {"final_attitude_error_rad"})
    keys |= {name for family in FAMILIES.values() for name in family.figures.names()}
    contract = CONTRACT.read_text()
    assert sorted(k for k in keys if f"`{k}`" not in contract) == []

"""The validation report is the same on every machine whose answers agree (issue 20).

* Printed numbers agree within the reproduction tolerance plus the resolution they were printed at, so a value
  that straddles a rounding boundary on another machine is the same line; a count must match.
* ``convexguid validate`` keeps every committed line a fresh run agrees with, and every committed picture a
  fresh one shows the same within the tolerance (the plot record each PNG carries; no version metadata): writing
  the same figure again leaves its file alone, bytes and modification time.
* ``convexguid validate --check`` writes nothing, passes on a problem file whose numbers moved by 1e-12 (what
  another machine's rounding does) and fails naming the line when a committed figure was edited.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

from convexguid.cli import main  # noqa: E402
from convexguid.figure_files import keep_unchanged_pictures, same_plot, write_figure  # noqa: E402
from convexguid.plot_record import PlotRecord  # noqa: E402
from convexguid.spec.loader import read_yaml_mapping  # noqa: E402
from convexguid.spec.perturb import perturb_inputs  # noqa: E402
from convexguid.validation.reproduction import PrintedNumber, lines_agree, reconcile, skeleton  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "problems" / "cai2018_flat_attitude.yaml"


# --- numbers as printed ------------------------------------------------------------------------------------------


def test_a_printed_number_carries_the_resolution_of_its_digits():
    number = PrintedNumber.parse("28.6425")
    assert number.value == 28.6425 and abs(number.resolution - 1e-4) < 1e-18
    assert abs(PrintedNumber.parse("4.22e-04").resolution - 1e-6) < 1e-20
    assert PrintedNumber.parse("2001").resolution == 0.0


def test_a_value_across_a_rounding_boundary_agrees_and_a_changed_count_does_not():
    assert lines_agree("energy 0.08114 N^2 m^2 s", "energy 0.08113 N^2 m^2 s")  # 0.081135 +/- round-off
    assert lines_agree("| maneuver_time_s | 28.6304 | 28.6425 |", "| maneuver_time_s | 28.6304 | 28.6426 |")
    assert lines_agree("error = 7.3e-07 rad", "error = 2.1e-07 rad")  # both round-off sized
    assert not lines_agree("4 corrections in 4 checks", "5 corrections in 4 checks")
    assert not lines_agree("| objective | 0.2607 | 0.260674 |", "| objective | 0.2607 | 0.260774 |")
    assert not lines_agree("status converged", "status max_iterations")
    # digits inside names are text, not numbers
    assert skeleton("body1 in wang2003-rendezvous, 3.5 deg.") == "body1 in wang2003-rendezvous, # deg."


def test_reconcile_keeps_agreeing_committed_lines_and_names_the_others():
    committed = "# report\n\n## case-a\n\n| x | 1.00001 |\n| n | 4 |\n\n## case-b\n\nold line\n"
    fresh = "# report\n\n## case-a\n\n| x | 1.00002 |\n| n | 5 |\n\n## case-b\n\nnew line\nextra 3\n"
    merged = reconcile(committed, fresh)
    assert "| x | 1.00001 |" in merged.text  # the committed digits stay
    assert "| n | 5 |" in merged.text and "new line" in merged.text
    described = [d.describe() for d in merged.differences]
    assert any(d.startswith("[case-a] committed: | n | 4 |") for d in described)
    assert any(d.startswith("[case-b]") and "new line" in d for d in described)
    assert reconcile(fresh, fresh).differences == () and reconcile(fresh, fresh).text == fresh
    assert reconcile(None, fresh).text == fresh


# --- pictures -----------------------------------------------------------------------------------------------------


def _plot(path: Path, shift: float, width: float = 1.5) -> Path:
    t = np.linspace(0.0, 10.0, 400)
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot(t, np.sin(t) + shift, lw=width)
    return write_figure(fig, path)


def test_writing_the_same_figure_again_leaves_the_file_alone(tmp_path):
    path = _plot(tmp_path / "a.png", 0.0)
    before, stamp = path.read_bytes(), path.stat().st_mtime_ns
    os.utime(path, ns=(stamp - 10**9, stamp - 10**9))  # a second older: a rewrite would show on any file system
    stamp = path.stat().st_mtime_ns
    for shift in (0.0, 1e-9):  # the same data, then data moved by round-off
        _plot(path, shift)
        assert path.read_bytes() == before and path.stat().st_mtime_ns == stamp
    assert b"Matplotlib" not in before  # no version metadata: one drawing is one file's bytes
    assert PlotRecord.of_file(path) is not None


def test_a_figure_is_rewritten_when_what_it_shows_changes_beyond_the_tolerance(tmp_path):
    path = _plot(tmp_path / "a.png", 0.0)
    record = PlotRecord.of_file(path)
    for shift, width in ((2e-3, 1.5), (0.0, 1.7)):  # a curve moved by a tenth of a point; a wider line
        stamp = path.stat().st_mtime_ns
        os.utime(path, ns=(stamp - 10**9, stamp - 10**9))
        _plot(path, shift, width)
        assert path.stat().st_mtime_ns != stamp - 10**9 and not PlotRecord.of_file(path).agrees(record)
    assert PlotRecord.decode(record.encode()).agrees(record)
    assert PlotRecord.decode("not a record") is None and PlotRecord.of_file(tmp_path / "missing.png") is None


def test_a_picture_redrawn_from_round_off_changed_data_keeps_its_committed_file(tmp_path):
    committed, fresh, moved = tmp_path / "committed", tmp_path / "fresh", tmp_path / "moved"
    for folder in (committed, fresh, moved):
        folder.mkdir()
    _plot(committed / "b.png", 0.0)
    nudged = _plot(fresh / "b.png", 1e-9)
    assert same_plot(nudged, committed / "b.png")
    keep_unchanged_pictures([nudged], committed)
    assert nudged.read_bytes() == (committed / "b.png").read_bytes()
    assert nudged.stat().st_mtime_ns == (committed / "b.png").stat().st_mtime_ns
    different = _plot(moved / "b.png", 0.5)
    assert not same_plot(different, committed / "b.png")
    keep_unchanged_pictures([different], committed)
    assert different.read_bytes() != (committed / "b.png").read_bytes()
    legacy = committed / "c.png"  # drawn before pictures carried their record: replaced once
    plt.imsave(legacy, np.zeros((3, 4)))
    assert not same_plot(_plot(fresh / "c.png", 0.0), legacy)


# --- validate --check ---------------------------------------------------------------------------------------------


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_validate_check_passes_on_round_off_and_names_an_edited_figure(tmp_path, capsys):
    out = tmp_path / "validation"
    out.mkdir()
    report = out / "REPORT.md"
    assert main(["validate", str(PAPER), "--report", str(report)]) == 0
    before = _tree(out)

    data, changed = perturb_inputs(read_yaml_mapping(PAPER, "a problem"), 1e-12, seed=3)
    assert changed > 5
    moved = tmp_path / "moved" / PAPER.name
    moved.parent.mkdir()
    moved.write_text(yaml.safe_dump(json.loads(json.dumps(data, default=float)), sort_keys=False))
    capsys.readouterr()
    assert main(["validate", "--check", str(moved), "--report", str(report)]) == 0
    assert "reproduced: every line agrees" in capsys.readouterr().out
    assert _tree(out) == before  # --check writes nothing

    assert main(["validate", str(moved), "--report", str(report)]) == 0
    assert _tree(out)["REPORT.md"] == before["REPORT.md"]  # a rerun on another machine's rounding: unchanged

    text = report.read_text()
    line = next(s for s in text.splitlines() if s.startswith("| map_alpha |"))
    report.write_text(text.replace(line, line.replace("0.913531", "0.923531")))
    capsys.readouterr()
    assert main(["validate", "--check", str(PAPER), "--report", str(report)]) == 1
    printed = capsys.readouterr().out
    assert "[cai2018-flat-attitude] committed: | map_alpha | 0.9135 | 0.923531 |" in printed
    assert "1 line(s) of" in printed

"""The README and the documentation's sources stay true to the project.

The site itself is built and checked by ``make docs-check`` (tools/docs-check), which
``make test`` runs once, on trixie; these tests are the quick part: the README's generated
tables are what the kept results give, the architecture lists every module, the manual carries
no dated measurements and every note says when and at which commit it was recorded.
"""

import json
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(ROOT / "tools"))

import validation_table  # noqa: E402

DATE = re.compile(r"\b20\d\d-\d\d-\d\d\b")


def test_readme_is_short():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= 250, f"README.md has {len(lines)} lines; the rest belongs in docs/"


def test_readme_tables_are_generated_from_the_kept_results():
    """README.md's validation and run-time tables are what tools/validation_table.py writes from
    docs/results/*/summary.json: edit the results (make results), never the table."""
    results = validation_table.load_results()
    assert {r["name"] for r in results} >= {"coarse", "default"}
    text = (ROOT / "README.md").read_text()
    assert validation_table.replace_blocks(text, validation_table.blocks(results)) == text
    assert validation_table.main(["--check"]) == 0


def test_kept_results_say_how_they_were_made():
    for result in validation_table.load_results():
        provenance = result["provenance"]
        for key in ("command", "commit", "date", "machine"):
            assert provenance.get(key), f"docs/results/{result['name']}/provenance.json lacks {key}"
        assert "tapecoil run" in provenance["command"]
        assert DATE.fullmatch(provenance["date"])
        assert result["summary"]["validation"], result["name"]


def test_every_check_of_every_kept_run_is_in_the_readme():
    text = (ROOT / "README.md").read_text()
    for result in validation_table.load_results():
        for row in result["summary"]["validation"]:
            label, _ = validation_table.split_label(row["label"])
            assert label in text, label
        assert result["provenance"]["commit"] in text


def _summary(rows):
    return {
        "ranks": 2,
        "wall_time": 125.0,
        "validation": rows,
        "coiling": {
            "run": {"mesh": "40 x 4", "dofs": 3645, "steps": 10, "wall_time": 30.0},
            "measures": {"radius": {"absolute": False, "source": "Eq. 4.3", "basis": "h per turn"}},
        },
        "deployment": {"run": {"steps": 5, "wall_time": 90.0}, "measures": {"growth": {"absolute": True}}},
    }


def _row(quantity, label, computed, reference, error, tolerance, passed, phase="coiling"):
    return {
        "phase": phase,
        "quantity": quantity,
        "label": label,
        "computed": computed,
        "reference": reference,
        "error": error,
        "tolerance": tolerance,
        "passed": passed,
    }


def test_the_table_reads_passes_failures_and_comparisons(tmp_path):
    """A row with a tolerance reads its error and pass or FAIL; one without reads as a comparison
    (no error, no pass mark); lengths are in mm; an absolute tolerance is not a percentage."""
    rows = [
        _row("radius", "outer coil radius [m]", 0.013310, 0.013273, 0.0028, 0.02, True),
        _row("turns", "smallest separation of distinct turns / h [-]", 0.0062, 1.0, 0.9938, None, None),
        _row("growth", "energy growth / stowed [-]", 4e-8, 0.0, 4e-8, 1e-3, True, "deployment"),
        _row("t90", "time to lambda = 0.9 [s]", 0.3647, 0.3914, 0.068, 0.05, False, "deployment"),
    ]
    directory = tmp_path / "results" / "coarse"
    directory.mkdir(parents=True)
    (directory / "summary.json").write_text(json.dumps(_summary(rows)))
    (directory / "provenance.json").write_text(
        json.dumps(
            {
                "command": "tapecoil run --mesh coarse",
                "commit": "abc1234",
                "date": "2026-01-02",
                "machine": "m",
            }
        )
    )
    results = validation_table.load_results(tmp_path / "results")
    table = validation_table.validation_block(results)
    assert "13.31 mm vs 13.27 mm: 0.28 %, pass" in table
    assert "| 0.0062 vs 1 |" in table  # a comparison: neither an error nor a pass mark
    assert "none (reported)" in table
    assert "4e-8 vs 0: 4e-8, pass" in table and "| 0.001 |" in table
    assert "**FAIL**" in table
    assert "`tapecoil run --mesh coarse`, commit abc1234, 2026-01-02" in table
    times = validation_table.run_times_block(results)
    assert "| 3,645 | 2 | 10, 30 s | 5, 1.5 min | 2.1 min | m |" in times
    page = validation_table.page(results)
    assert "**Reference.** Eq. 4.3." in page and "h per turn" in page
    readme = tmp_path / "README.md"
    readme.write_text(
        "head\n"
        + "\n".join(
            f"{validation_table.begin_marker(b)}\nold\n{validation_table.end_marker(b)}"
            for b in validation_table.BLOCKS
        )
        + "\ntail\n"
    )
    args = ["--readme", str(readme), "--results", str(tmp_path / "results")]
    assert validation_table.main([*args, "--check"]) == 1
    assert validation_table.main(args) == 0
    assert validation_table.main([*args, "--check"]) == 0
    assert "old" not in readme.read_text() and readme.read_text().endswith("tail\n")


def test_architecture_lists_every_module():
    """docs/architecture.md names every module of the package (find solver -name '*.py')."""
    text = (DOCS / "architecture.md").read_text()
    missing = [
        str(path.relative_to(ROOT))
        for path in sorted((ROOT / "solver" / "tapecoil").rglob("*.py"))
        if path.stem != "__init__" and not re.search(rf"\b{re.escape(path.stem)}\b", text)
    ]
    assert not missing, f"docs/architecture.md does not name {missing}"


def _manual_pages():
    return sorted([*(DOCS / "guide").glob("*.md"), *(DOCS / "theory").glob("*.md"), DOCS / "index.md"])


@pytest.mark.parametrize("page", _manual_pages(), ids=lambda p: str(p.relative_to(DOCS)))
def test_the_manual_carries_no_dated_measurement(page):
    """Dated measurements live in docs/notes/ with their commit and command, not in the manual."""
    dates = DATE.findall(page.read_text())
    assert not dates, f"{page.relative_to(ROOT)} carries dates {dates}: move the measurement to docs/notes/"


@pytest.mark.parametrize(
    "note", sorted(p for p in (DOCS / "notes").glob("*.md") if p.name != "index.md"), ids=lambda p: p.name
)
def test_every_note_says_when_and_at_which_commit(note):
    text = note.read_text()
    assert "Provenance" in text and DATE.search(text), note.name
    assert re.search(r"commit `[0-9a-f]{7,}`", text), note.name


def test_every_note_is_in_the_notes_index():
    index = (DOCS / "notes" / "index.md").read_text()
    for note in (DOCS / "notes").glob("*.md"):
        if note.name != "index.md":
            assert re.search(rf"^{re.escape(note.stem)}$", index, re.M), (
                f"{note.name} is not in docs/notes/index.md"
            )


def test_the_readme_pictures_exist():
    text = (ROOT / "README.md").read_text()
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert pictures
    for picture in pictures:
        assert (ROOT / picture).is_file(), picture


def test_a_demo_becomes_a_page_of_text_and_code():
    """The demos' conversion (docs/conf.py): markdown cells as text, code cells as Python blocks."""
    pytest.importorskip("jupytext")
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_conf_demo", DOCS / "conf.py")
    source = (DOCS / "conf.py").read_text().split("\ngenerate()\n")[0]  # the functions, not the build
    module = importlib.util.module_from_spec(spec)
    module.__file__ = str(DOCS / "conf.py")
    exec(compile(source, str(DOCS / "conf.py"), "exec"), module.__dict__)
    page = module.demo_page(ROOT / "demos" / "tape_fold.py")
    assert page.startswith("# Folding a tape spring through the snap")
    assert "$$ M^* = (1 + \\nu) D \\alpha" in page
    assert "```python\nimport json" in page
    assert "# %%" not in page

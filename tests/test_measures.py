"""The Measure type: errors, pass marks, and the rows the summary and the report are made of."""

import math

import pytest

from tapecoil.measures.measure import Measure, is_measure, validation_rows


def test_relative_and_absolute_errors_and_pass_marks():
    m = Measure("outer coil radius [m]", 0.0133, 0.0132727, 0.02, "Sec. 2")
    assert math.isclose(m.error, abs(0.0133 - 0.0132727) / 0.0132727)
    assert m.passed is True
    far = Measure("x [-]", 1.2, 1.0, 0.1)
    assert far.passed is False
    growth = Measure("growth [-]", 2e-3, 0.0, 1e-3, absolute=True)
    assert growth.error == 2e-3 and growth.passed is False
    reported = Measure("energy [J]", 1.3, 1.32)
    assert reported.passed is None


def test_a_quantity_not_reached_fails_and_has_no_error():
    m = Measure("time to lambda = 0.9 [s]", None, 0.38, 0.05)
    assert m.error is None and m.passed is False
    assert Measure("t [s]", float("nan"), 1.0, 0.05).passed is False


def test_rows_come_from_the_measures_in_order_and_nothing_else():
    measures = {
        "hub_angle": 36.0,
        "b": Measure("b [m]", 2.0, 2.0, 0.1, extra={"worst": 2.5}).to_dict(),
        "profile": {"computed": [1, 2]},
        "a": Measure("a [m]", 1.0, 1.1, None).to_dict(),
    }
    rows = validation_rows("coiling", measures)
    assert [r["quantity"] for r in rows] == ["b", "a"]
    assert rows[0]["passed"] is True and rows[1]["passed"] is None and rows[1]["tolerance"] is None
    assert measures["b"]["worst"] == 2.5 and is_measure(measures["b"]) and not is_measure(measures["profile"])


def test_a_bound_is_held_or_read():
    """A lower bound: the shortfall below it is the error, held to 0; without a tolerance the
    value is a reading, reported without a pass mark; the command line says which."""
    from tapecoil.app.commands.runs import _measure_line

    held = Measure("separation / h [-]", 0.7, 0.9, 0.0, bound="lower")
    assert held.error == pytest.approx(0.2) and held.passed is False
    assert Measure("separation / h [-]", 0.95, 0.9, 0.0, bound="lower").passed is True
    read = Measure("separation / h [-]", 0.7, 0.9, None, bound="lower").to_dict()
    assert read["passed"] is None and read["bound"] == "lower"
    with pytest.raises(ValueError, match="tolerance is 0"):
        Measure("separation / h [-]", 0.7, 0.9, 0.1, bound="lower")
    assert "at least" in _measure_line("closest_turns", held.to_dict())
    assert _measure_line("closest_turns", read).split()[-1] == "reported"

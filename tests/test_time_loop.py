"""The deployment's time loop, whichever model it steps: its legs and the refusal of a step that
makes energy."""

import pytest

from tapecoil.phases.time_loop import ENERGY_GROWTH, energy_refusal, smallest_time_step, time_legs


def test_the_release_is_stepped_finely_then_the_steps_may_grow():
    assert time_legs(0.002, 0.6, 1e-4, 1e-3) == [(0.002, 1e-4), (0.6, 1e-3)]
    # a release a twentieth of whose length is below the first step is stepped in twentieths
    assert time_legs(0.001, 0.6, 1e-4, 1e-3)[0] == (0.001, pytest.approx(5e-5))
    # no release: one leg; a run shorter than the release ends with it
    assert time_legs(0.0, 0.6, 1e-4, 1e-3) == [(0.6, 1e-3)]
    assert time_legs(0.002, 0.001, 1e-4, 1e-3)[0][0] == 0.001
    assert smallest_time_step(0.6, 1e-4) == pytest.approx(1e-7)


def test_a_step_that_makes_energy_is_refused_the_loads_work_counted():
    stowed = 1.3
    # dissipating, or growing within the bound: accepted
    assert energy_refusal(1.30, 1.29, 0.0, stowed) is None
    assert energy_refusal(1.30, 1.30 + 0.9 * ENERGY_GROWTH * stowed, 0.0, stowed) is None
    # beyond it: refused, the growth named as a share of the stowed energy
    message = energy_refusal(1.30, 1.30 + 2 * ENERGY_GROWTH * stowed, 0.0, stowed)
    assert message is not None and f"{2 * ENERGY_GROWTH:.3g} of the stowed energy" in message
    # the same rise paid for by the loads' work (a release's hold, gravity) is no growth
    assert energy_refusal(1.30, 1.30 + 2 * ENERGY_GROWTH * stowed, 2 * ENERGY_GROWTH * stowed, stowed) is None

"""Generalized-alpha time integration (tapecoil.core.timeint) on single-dof oscillators.

Each cell of a DG0 space is an independent oscillator m q'' + k q = 0; the integrator's
classical properties (Chung and Hulbert 1993) are checked against their closed forms.
"""

import math

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from tapecoil.core.newton import SNESSolver
from tapecoil.core.timeint import AlphaParameters, GeneralizedAlpha


def test_parameters_from_the_spectral_radius():
    p = AlphaParameters.from_spectral_radius(1.0)
    assert (p.alpha_m, p.alpha_f, p.gamma, p.beta) == pytest.approx((0.5, 0.5, 0.5, 0.25))
    for rho in (0.0, 0.3, 0.8):
        p = AlphaParameters.from_spectral_radius(rho)
        # second-order accuracy and unconditional stability (Chung-Hulbert)
        assert p.gamma == pytest.approx(0.5 - p.alpha_m + p.alpha_f)
        assert p.alpha_m <= p.alpha_f <= 0.5
        assert p.beta >= 0.25 + 0.5 * (p.alpha_f - p.alpha_m)
    with pytest.raises(ValueError, match="rho_inf"):
        AlphaParameters.from_spectral_radius(1.5)


def oscillators(omegas, rho_inf, dt, steps, q0=1.0):
    """Free vibration of oscillators with angular frequencies ``omegas`` from q = q0, v = 0."""
    mesh = dolfinx.mesh.create_interval(MPI.COMM_SELF, len(omegas), [0.0, 1.0])
    V = dolfinx.fem.functionspace(mesh, ("DG", 0))
    stiffness = dolfinx.fem.Function(V)
    stiffness.x.array[:] = np.asarray(omegas) ** 2  # unit mass
    q = dolfinx.fem.Function(V)
    q.x.array[:] = q0
    ti = GeneralizedAlpha(q, rho_inf)
    ti.a_old.x.array[:] = -stiffness.x.array * q0
    dq = ufl.TestFunction(V)
    F = ti.a_m * dq * ufl.dx + ti.force_average(stiffness * q * dq * ufl.dx)
    jacobian = ufl.derivative(F, q, ufl.TrialFunction(V))
    solver = SNESSolver(F, jacobian, q, [], prefix="test_dynamics_", rtol=1e-12, atol=1e-300)
    ti.set_step(dt)
    out = [q.x.array.copy()]
    energy = [0.5 * stiffness.x.array * q0**2]
    for _ in range(steps):
        ti.predict(dt)
        assert solver.solve().converged
        ti.advance()
        out.append(q.x.array.copy())
        energy.append(0.5 * ti.v_old.x.array**2 + 0.5 * stiffness.x.array * q.x.array**2)
    solver.destroy()
    return np.array(out), np.array(energy)


def test_trapezoidal_rule_conserves_energy_and_has_its_period_error():
    """rho_inf = 1: energy exact; the phase lags by the trapezoidal rule's known amount."""
    omega, dt, steps = 2 * math.pi, 0.02, 200  # four periods, omega dt = 0.126
    q, energy = oscillators([omega], 1.0, dt, steps)
    assert np.allclose(energy, energy[0], rtol=1e-10)
    # the discrete solution is cos(Omega t) with tan(Omega dt / 2) = omega dt / 2
    discrete = 2 / dt * math.atan(omega * dt / 2)
    t = dt * np.arange(steps + 1)
    assert np.allclose(q[:, 0], np.cos(discrete * t), atol=1e-8)
    assert not np.allclose(q[:, 0], np.cos(omega * t), atol=1e-2)  # the lag is there and visible


def test_high_frequencies_are_damped_by_rho_inf_low_ones_kept():
    """The stiff oscillator decays at rho_inf per step; the slow one keeps its energy.

    For omega dt -> infinity the three eigenvalues of the amplification matrix all tend to
    -rho_inf, so the amplitude goes as n^2 rho_inf^n: over steps 200 to 240 the polynomial
    factor adds under 1 % to the measured rate.
    """
    dt = 1.0
    for rho in (0.0, 0.5, 0.8):
        q, energy = oscillators([1e6, 1e-2], rho, dt, 240)
        if rho == 0.0:
            assert np.all(np.abs(q[4:, 0]) < 1e-9)  # annihilated within a few steps
        else:
            rate = (abs(q[240, 0]) / abs(q[200, 0])) ** (1 / 40)
            assert rate == pytest.approx(rho, rel=0.015), rho
        # the slow oscillator: energy kept to second order in omega dt
        assert energy[-1, 1] == pytest.approx(energy[0, 1], rel=1e-4)


def one_step_error(rho_inf, omega, dt, t0=0.3):
    """(estimated, actual) local error of one step of q'' + omega^2 q = 0 from the exact state at t0."""
    mesh = dolfinx.mesh.create_interval(MPI.COMM_SELF, 1, [0.0, 1.0])
    V = dolfinx.fem.functionspace(mesh, ("DG", 0))
    q = dolfinx.fem.Function(V)
    q.x.array[:] = math.cos(omega * t0)
    ti = GeneralizedAlpha(q, rho_inf)
    ti.v_old.x.array[:] = -omega * math.sin(omega * t0)
    ti.a_old.x.array[:] = -(omega**2) * math.cos(omega * t0)
    dq = ufl.TestFunction(V)
    F = ti.a_m * dq * ufl.dx + ti.force_average(omega**2 * q * dq * ufl.dx)
    solver = SNESSolver(
        F, ufl.derivative(F, q, ufl.TrialFunction(V)), q, [], prefix="test_error_", rtol=1e-14, atol=1e-300
    )
    ti.set_step(dt)
    ti.predict(dt)
    assert solver.solve().converged
    estimate = ti.local_error()[0]
    solver.destroy()
    return estimate, q.x.array[0] - math.cos(omega * (t0 + dt))


def test_the_local_error_estimate_is_the_error_of_a_step():
    """Zienkiewicz and Xie's estimate (beta - 1/6) dt^2 (a_{n+1} - a_n) against the true error.

    For rho_inf = 1 (Newmark's average acceleration) it is the leading term of the local error:
    the ratio tends to 1 as dt -> 0. For rho_inf < 1 the estimate keeps the error's order, dt^3,
    and over-estimates it by a bounded factor (1.43 for rho_inf = 0.5, from the same one-step
    computation in closed form), so that steps sized by it are on the safe side.
    """
    omega = 2 * math.pi
    ratios = [np.divide(*one_step_error(1.0, omega, dt)) for dt in (0.03, 0.003)]
    assert ratios[0] == pytest.approx(1.0, abs=0.06)
    assert ratios[1] == pytest.approx(1.0, abs=0.005)
    for rho in (0.5, 0.0):
        estimates, actual = zip(*(one_step_error(rho, omega, dt) for dt in (0.004, 0.002)), strict=True)
        assert 1.0 < estimates[0] / actual[0] < 1.5  # over-estimated, within a bounded factor
        assert estimates[0] / estimates[1] == pytest.approx(8.0, rel=0.02)  # third order

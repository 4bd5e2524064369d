"""Laminated walls: classical lamination theory, the orthotropic plate formulas, the [laminate]
configuration and the shell's laminate law."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from tapecoil import theory as th
from tapecoil.config import ConfigError, config_from_dict, load_config, to_toml
from tapecoil.config.toml import tomllib
from tapecoil.theory.laminate import Wall

CFRP = Path(__file__).resolve().parents[1] / "demos" / "cfrp_tape.toml"
DEG = math.pi / 180


def cross_ply(angles_deg, E1=128e9, E2=6.5e9, nu12=0.33, G12=4.5e9, h=71e-6):
    n = len(angles_deg)
    return Wall.from_plies(
        [E1] * n,
        [E2] * n,
        [nu12] * n,
        [G12] * n,
        [G12] * n,
        [G12] * n,
        [a * DEG for a in angles_deg],
        [h / n] * n,
    )


# --- classical lamination theory ---------------------------------------------------------


def test_plies_of_an_isotropic_material_make_the_isotropic_wall():
    E, nu, h = 130e9, 0.3, 1e-4
    G = E / (2 * (1 + nu))
    plies = Wall.from_plies(
        [E] * 3, [E] * 3, [nu] * 3, [G] * 3, [G] * 3, [G] * 3, [0.3, -1.1, 2.0], [h / 3] * 3
    )
    iso = Wall.isotropic(E, nu, h)
    for name in ("A", "B", "D", "H"):
        assert np.allclose(
            getattr(plies, name), getattr(iso, name), rtol=0, atol=1e-12 * np.abs(iso.A).max()
        ), name
    expected = th.Bending.isotropic(th.flexural_rigidity(E, h, nu), nu)
    assert tuple(vars(iso.bending).values()) == pytest.approx(tuple(vars(expected).values()), rel=1e-12)
    assert iso.axial_modulus == pytest.approx(E, rel=1e-12)


def test_quasi_isotropic_layup_has_an_isotropic_membrane_stiffness():
    """[0/45/-45/90]s: A is isotropic (Jones, Sec. 4.3), though D is not."""
    A = cross_ply([0, 45, -45, 90, 90, -45, 45, 0]).A
    assert A[0, 0] == pytest.approx(A[1, 1], rel=1e-12)
    assert A[2, 2] == pytest.approx((A[0, 0] - A[0, 1]) / 2, rel=1e-12)
    assert abs(A[0, 2]) < 1e-12 * A[0, 0] and abs(A[1, 2]) < 1e-12 * A[0, 0]


def test_cross_ply_stiffness_by_hand():
    """[0/90]s and the unsymmetric [0/90] against their integrals through the thickness."""
    E1, E2, nu12, h = 128e9, 6.5e9, 0.33, 71e-6
    d = 1 - nu12**2 * E2 / E1
    Q11, Q22 = E1 / d, E2 / d
    sym = cross_ply([0, 90, 90, 0])
    outer, inner = ((h / 2) ** 3 - (h / 4) ** 3) * 2 / 3, (h / 4) ** 3 * 2 / 3
    assert sym.D[0, 0] == pytest.approx(Q11 * outer + Q22 * inner, rel=1e-12)
    assert sym.D[1, 1] == pytest.approx(Q22 * outer + Q11 * inner, rel=1e-12)
    assert np.abs(sym.B).max() == 0.0
    # the brief's example (Wilson 2017): D11 = 0.0034 N m, D22 = 0.00065 N m
    assert sym.bending.D11 == pytest.approx(0.0034, rel=0.01)
    assert sym.bending.D22 == pytest.approx(0.00065, rel=0.01)
    unsym = cross_ply([0, 90])  # the 0 ply below the mid-plane
    assert unsym.B[0, 0] == pytest.approx((Q22 - Q11) * h**2 / 8, rel=1e-12)
    assert unsym.B[1, 1] == pytest.approx(-unsym.B[0, 0], rel=1e-12)
    # relaxing the in-plane forces softens the bending of an unsymmetric wall only
    assert unsym.bending.D11 < unsym.D[0, 0]
    assert sym.bending.D11 == pytest.approx(sym.D[0, 0], rel=1e-12)


def test_a_ply_turned_by_90_degrees_swaps_the_axes():
    Q0, Q90 = (
        th.ply_stiffness(128e9, 6.5e9, 0.33, 4.5e9, 0.0),
        th.ply_stiffness(128e9, 6.5e9, 0.33, 4.5e9, math.pi / 2),
    )
    assert Q90[0, 0] == pytest.approx(Q0[1, 1]) and Q90[1, 1] == pytest.approx(Q0[0, 0])
    assert Q90[0, 1] == pytest.approx(Q0[0, 1]) and Q90[2, 2] == pytest.approx(Q0[2, 2])
    assert abs(Q90[0, 2]) < 1e-6 * Q0[0, 0]


def test_a_wall_that_stores_no_energy_is_refused():
    bad = Wall.from_matrices(np.eye(3), np.zeros((3, 3)), np.diag([1.0, -1.0, 1.0]), np.eye(2), 1e-4)
    with pytest.raises(ValueError, match="not positive definite"):
        bad.check()


# --- the orthotropic plate formulas (physics brief Sec. 10) ------------------------------


def test_formulas_of_an_isotropic_wall_are_the_isotropic_ones():
    D, nu, R, rho, alpha = 0.0119, 0.3, 0.0151, 0.0128, 2.356
    b = th.Bending.isotropic(D, nu)
    assert th.energy_density(rho, R, b) == pytest.approx(
        0.5 * D * (1 / rho**2 + 1 / R**2 + 2 * nu / (rho * R))
    )
    assert th.coil_energy_at_R(b, R) == pytest.approx(th.opposite_sense_energy_density(D, nu, R))
    assert th.fold_moment(b, alpha) == pytest.approx((1 + nu) * D * alpha)
    assert th.fold_moment(b, alpha, "equal") == pytest.approx((1 - nu) * D * alpha)
    assert th.fold_radius(b, R) == pytest.approx(R)


def test_fold_radius_and_plateau_minimise_the_fold_energy():
    """A fold of radius rho stores b w(rho) rho per radian turned: its minimum over rho is the
    moment plateau and its argument the fold radius (Seffen and Pellegrino's argument)."""
    wall, R, alpha = cross_ply([0, 90, 90, 0]), 0.0127, math.pi / 2
    bending = wall.bending
    best = minimize_scalar(
        lambda rho: R * alpha * th.energy_density(rho, R, bending) * rho,
        bounds=(0.2 * R, 20 * R),
        method="bounded",
    )
    assert best.x == pytest.approx(th.fold_radius(bending, R), rel=1e-4)
    assert best.fun == pytest.approx(th.fold_moment(bending, alpha), rel=1e-8)
    assert th.fold_radius(bending, R) == pytest.approx(R * math.sqrt(bending.D11 / bending.D22))
    # the equal sense: the same minimum with w's coupling term of the other sign
    best = minimize_scalar(
        lambda rho: R * alpha * th.energy_density(rho, R, bending, "equal") * rho,
        bounds=(0.2 * R, 20 * R),
        method="bounded",
    )
    assert best.x == pytest.approx(th.fold_radius(bending, R), rel=1e-4)
    assert best.fun == pytest.approx(th.fold_moment(bending, alpha, "equal"), rel=1e-8)


@pytest.mark.parametrize("sense", ["opposite", "equal"])
def test_orthotropic_stored_energy_is_the_spiral_integral(sense):
    bending, R, alpha, r_hub, h = cross_ply([0, 90, 90, 0]).bending, 0.0127, math.pi / 2, 0.0127, 71e-6
    theta = 36.0
    rho0 = r_hub + h / 2
    rho1 = rho0 + h * theta / (2 * math.pi)
    integral = (
        quad(lambda r: th.energy_density(r, R, bending, sense) * r * R * alpha, rho0, rho1)[0]
        * 2
        * math.pi
        / h
    )
    assert th.stored_energy(theta, r_hub, h, R, alpha, bending, sense) == pytest.approx(integral, rel=1e-10)


def test_orthotropic_coiling_tension_is_the_configurational_balance():
    """T = kappa dU/dkappa - U with U = b w: (b/2)(D11/rho^2 - D22/R^2) (physics brief Sec. 10)."""
    bending, R, alpha, rho = cross_ply([0, 90, 90, 0]).bending, 0.0127, math.pi / 2, 0.0128
    b = R * alpha

    def U(kappa):
        return b * th.energy_density(1 / kappa, R, bending)

    k, dk = 1 / rho, 1e-3 / rho
    balance = k * (U(k + dk) - U(k - dk)) / (2 * dk) - U(k)
    assert th.coiling_tension_bending(bending, alpha, R, rho) == pytest.approx(balance, rel=1e-6)


def test_laminate_coil_stresses_use_the_face_ply():
    wall, R, rho, h = cross_ply([0, 90, 90, 0]), 0.0127, 0.0128, 71e-6
    Q = wall.stiffness_at(h / 2)
    assert Q[0, 0] > 10 * Q[1, 1]  # the outer ply runs along the tape
    sx, sy = th.coil_stresses(rho, R, Q, h / 2)
    assert sx == pytest.approx(Q[0, 0] * h / 2 / rho + Q[0, 1] * h / 2 / R)
    assert sy == pytest.approx(Q[1, 0] * h / 2 / rho + Q[1, 1] * h / 2 / R)


# --- the [laminate] configuration --------------------------------------------------------


def cfrp_data():
    with CFRP.open("rb") as f:
        return tomllib.load(f)


def test_cfrp_demo_configuration():
    config = load_config(CFRP)
    assert config.laminate.kind == "plies"
    bending = config.wall.bending
    assert (bending.D11, bending.D22) == pytest.approx((0.0034, 0.00065), rel=0.01)
    # written back and read again: the same wall
    again = config_from_dict(tomllib.loads(to_toml(config)))
    assert np.array_equal(again.wall.D, config.wall.D)
    assert "E =" not in to_toml(config).split("[laminate]")[0].split("[tape]")[1]


def test_matrices_give_the_wall_as_stated():
    wall = cross_ply([0, 90, 90, 0])
    upper = [0, 1, 2, 4, 5, 8]  # 11, 12, 16, 22, 26, 66 of a flattened 3 x 3
    data = {
        "tape": {"R": 0.0127, "alpha": 1.5707963, "h": 71e-6, "rho_l": 2.2e-3},
        "laminate": {"kind": "matrices", "A": list(wall.A.flat[upper]), "D": list(wall.D.flat[upper])},
        "hub": {"radius": 0.0127},
    }
    config = config_from_dict(data)
    assert np.allclose(config.wall.D, wall.D, rtol=1e-14, atol=0)
    assert config.wall.H[0, 0] == pytest.approx(5 / 6 * wall.A[2, 2])
    assert config.wall.stiffness_at(0.0) == pytest.approx(12 * wall.D / wall.h**3)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: d["tape"].update(E=70e9), r"tape\.E does not act with a laminate"),
        (
            lambda d: d["tape"].update(h=1e-4),
            r"laminate\.thicknesses add up to 7\.1e-05 m, not tape\.h = 0\.0001 m",
        ),
        (
            lambda d: d["laminate"].update(kind="isotropic"),
            r"laminate\.angles does not act with laminate\.kind = 'isotropic'",
        ),
        (
            lambda d: d["laminate"].update(A=[1.0] * 6),
            r"laminate\.A does not act with laminate\.kind = 'plies'",
        ),
        (
            lambda d: d["laminate"].update(thicknesses=[71e-6 / 3] * 3),
            r"laminate\.thicknesses has 3 values for 4 plies",
        ),
        (
            lambda d: d["laminate"].update(E1=[1e9, 2e9]),
            r"laminate\.E1 must hold one value for every ply or one per ply",
        ),
        (lambda d: d["laminate"].update(nu12=[5.0]), r"laminate\.nu12 = 5 is out of range .* sqrt\(E1/E2\)"),
        (lambda d: d["laminate"].pop("E2"), r"laminate\.E2 is needed"),
        (lambda d: d["laminate"].update(G12=[-1.0]), r"laminate\.G12 = \[-1\.0\] is out of range"),
    ],
)
def test_laminate_configuration_errors(change, message):
    data = cfrp_data()
    change(data)
    with pytest.raises(ConfigError, match=message):
        config_from_dict(data)


# --- the shell's laminate law -------------------------------------------------------------


def _shells(materials):
    """Shells of the benchmark strip (4 x 10 elements) sharing one mesh, one per material."""
    from mpi4py import MPI

    from tapecoil.geometry.meshes import MeshResolution, create_strip_mesh
    from tapecoil.geometry.surfaces import StripGeometry
    from tapecoil.models.shell import NaghdiShell

    strip = create_strip_mesh(MPI.COMM_WORLD, StripGeometry.from_config(load_config()), MeshResolution(4, 10))
    return [NaghdiShell(strip, m, director_frame="global") for m in materials]


def _random_state(model, seed, size=1e-4):
    """Random nodal displacements of ``size`` [m] and director angles of 100 size [rad]."""
    from tapecoil.models.nodes import Nodes

    nodes = Nodes(model)
    rng = np.random.default_rng(seed)
    step = np.zeros_like(model.q.x.array)
    step[nodes.u_dofs] = size * rng.standard_normal(nodes.u_dofs.shape)
    step[nodes.theta_dofs] = 100 * size * rng.standard_normal(nodes.theta_dofs.shape)
    return step


def test_laminate_law_of_an_isotropic_wall_is_the_isotropic_law():
    """The orthonormal frame and the matrices reproduce the metric form of the isotropic law,
    part by part, on the curved strip in a large random deformation."""
    from tapecoil.core.dofs import global_scalar
    from tapecoil.models.shell import LaminateMaterial, ShellMaterial

    E, nu, h = 130e9, 0.3, 1e-4
    iso, lam = _shells([ShellMaterial(E, nu, h), LaminateMaterial(Wall.isotropic(E, nu, h))])
    state = _random_state(iso, 7)
    iso.q.x.array[:] = state
    lam.q.x.array[:] = state
    for a, b in zip(iso.energy_forms(), lam.energy_forms(), strict=True):
        ea, eb = global_scalar(a, iso.mesh.comm), global_scalar(b, lam.mesh.comm)
        assert ea > 0 and eb == pytest.approx(ea, rel=1e-10)


@pytest.mark.parametrize("angles", [[0, 90], [30, -60, 10]])
def test_laminate_secant_work_is_the_exact_energy_change(angles):
    """The deployment's energy-consistent work with a coupled (B != 0) and a skewed (D16 != 0)
    laminate: the change of the strain energy over a step, for a step of any size."""
    import dolfinx

    from tapecoil.core.dofs import global_scalar
    from tapecoil.models.shell import LaminateMaterial

    wall = cross_ply(angles, h=1e-4)
    assert np.abs(wall.B).max() > 0 and abs(wall.D[0, 2]) + abs(wall.B[0, 2]) > 0
    (model,) = _shells([LaminateMaterial(wall)])
    q = model.q.x.array
    q_old = dolfinx.fem.Function(model.W)
    q_old.x.array[:] = _random_state(model, 1)
    energy = dolfinx.fem.form(model.strain_energy)
    work = dolfinx.fem.form(sum(model.energy_secant_forms(q_old)))
    for size in (1e-6, 1e-4):
        step = _random_state(model, 2, size)
        q[:] = q_old.x.array
        e0 = global_scalar(energy, model.mesh.comm)
        q[:] = q_old.x.array + step
        e1 = global_scalar(energy, model.mesh.comm)
        f = dolfinx.fem.Function(model.W)
        dolfinx.fem.assemble_vector(f.x.array, work)
        f.x.scatter_reverse(dolfinx.la.InsertMode.add)
        n = model.W.dofmap.index_map.size_local * model.W.dofmap.index_map_bs
        local = float(np.dot(f.x.array[:n], step[:n]))
        assert model.mesh.comm.allreduce(local) == pytest.approx(e1 - e0, rel=1e-9)


def test_cfrp_tape_bends_as_a_beam_of_its_axial_modulus():
    """The CFRP tape clamped, a small end moment: the end rotation against M L / (E_x I) with
    E_x = 1 / (h (A^-1)_11), the laminate's axial modulus (the arc section bends by
    stretching its wall: the membrane stiffness A in the shell's orthonormal frame)."""
    from tapecoil.verification.cases import run_case

    result = run_case("tape-linear", load_config(CFRP), "coarse")
    failed = [(c.name, c.computed, c.reference) for c in result.checks if not c.passed]
    assert not failed, failed
    assert result.info["energy_split"]["membrane"] > 0.99


# --- a laminated tape coiled -------------------------------------------------------------


def cfrp_short(hub_angle: float, L: float = 0.15):
    """The CFRP tape of the demo, shortened, on the coarse mesh: a run of seconds."""
    import dataclasses

    cfg = load_config(CFRP)
    return dataclasses.replace(
        cfg,
        tape=dataclasses.replace(cfg.tape, L=L),
        coiling=dataclasses.replace(cfg.coiling, hub_angle=hub_angle),
        mesh=dataclasses.replace(cfg.mesh, preset="coarse"),
    )


@pytest.mark.slow
def test_cfrp_tape_coils_to_its_orthotropic_plate_state(tmp_path):
    """A turn and a half of the [0/90]s tape: the stored energy of the coiled length within 5 %
    of the orthotropic plate estimate (physics brief Sec. 10), the wound curvature and the face
    ply's stresses within the isotropic coil's tolerances."""
    from mpi4py import MPI

    from tapecoil.phases.coiling_run import run_coiling

    config = cfrp_short(8.0)
    summary, _ = run_coiling(config, tmp_path, MPI.COMM_SELF, progress=False)
    assert summary["completed"]
    m = summary["measures"]
    for key in ("stored_energy_coiled", "curvature_longitudinal", "stress_x", "stress_y"):
        assert m[key]["passed"], (key, m[key]["computed"], m[key]["reference"])
    assert m["stored_energy_coiled"]["error"] < 0.05
    # the reference is the orthotropic one: an isotropic wall of D = D11, nu = D12 / D11 (so
    # D22 = D11 across the width) stores 1.7 times as much per unit area, far outside the 5 %
    bending = config.wall.bending
    rho = config.hub.radius + config.tape.h / 2
    iso = th.Bending.isotropic(bending.D11, bending.D12 / bending.D11)
    R = config.tape.R
    assert th.energy_density(rho, R, iso) > 1.5 * th.energy_density(rho, R, bending)


@pytest.mark.mpi
def test_cfrp_tape_coils_on_two_ranks_as_on_one(coil_last_row):
    from mpi4py import MPI

    config = cfrp_short(0.5)
    parallel, serial = coil_last_row(config, MPI.COMM_WORLD, 0.5), coil_last_row(config, MPI.COMM_SELF, 0.5)
    assert MPI.COMM_WORLD.size > 1
    for key in ("strain_energy", "bending_energy", "membrane_energy", "coiled_length", "end_slide"):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-6), key


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["coarse", "default"])
def test_cfrp_tape_folds_at_its_orthotropic_plateau(preset):
    """The [0/90]s tape's opposite-sense fold (physics brief Sec. 10): the moment plateau
    alpha (sqrt(D11 D22) + D12) within 5 %, the fold radius R sqrt(D11/D22) = 2.3 R within 10 %,
    the section flat in the fold. The fold's energy per unit area is not held to the 5 % of the
    isotropic case: it comes out 6 % below w(R sqrt(D11/D22)) on both meshes (docs/notes/laminates.md)."""
    from tapecoil.verification.cases import run_case

    result = run_case("tape-fold", load_config(CFRP), preset)
    checks = {c.name.split(" /")[0].split(" in the")[0]: c for c in result.checks}
    assert result.info["snap_angle"] is not None  # it went through the snap
    for name in ("moment plateau", "fold radius", "transverse curvature"):
        assert checks[name].passed, (name, checks[name].computed)
    # the fold is 2.3 R, not the isotropic tape's R: the check does see D11 / D22
    config = load_config(CFRP)
    measured = checks["fold radius"].computed * th.fold_radius(config.wall.bending, config.tape.R)
    assert measured > 2 * config.tape.R

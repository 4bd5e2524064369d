"""Analytic theory of tape-spring coiling and deployment (physics brief, thesis equations).

All functions take and return SI units. Equation numbers are the thesis's; where the thesis
is inconsistent the physics brief's consistent form is used and the docstring says so.

numpy and scipy only, so that ``tapecoil theory`` starts without DOLFINx. By job:

- :mod:`~tapecoil.theory.laminate`: the wall's stiffness (A, B, D, H) from E and nu, from plies
  (classical lamination theory) or given, and the rigidities :class:`Bending` of the formulas;
- :mod:`~tapecoil.theory.plate`: rigidity, energy densities, section and fold moments, coil
  stresses (and their sign convention), ploy length;
- :mod:`~tapecoil.theory.coil_geometry`: turn radii, coiled length against hub rotation and coil
  radius, stored energy;
- :mod:`~tapecoil.theory.coiling_tension`: the coiling regimes and their tension laws;
- :mod:`~tapecoil.theory.edge_layer`: the free edges of a flattened coil (their lift, the
  energy they relieve, what they add to the coiling tension);
- :mod:`~tapecoil.theory.deployment`: the deployment rate, its closed forms and the ODE;
- :mod:`~tapecoil.theory.table`: :class:`Prediction` and :func:`predictions`, the table.

Every name is available here too: ``from tapecoil import theory; theory.stored_energy(...)``.
"""

from tapecoil.theory.coil_geometry import (
    coil_radius_during_deployment,
    coiled_length_from_radius,
    coiled_length_from_rotation,
    max_hub_angle,
    outer_radius_after_rotation,
    radius_from_coiled_length,
    rotation_for_coiled_length,
    stored_energy,
    turn_radius,
)
from tapecoil.theory.coiling_tension import (
    UNIQUENESS_LIMIT,
    coiling_regime,
    coiling_tension_bending,
    coiling_tension_growing,
    coiling_tension_tension_dominated,
    required_coiling_tension,
)
from tapecoil.theory.deployment import (
    DeploymentSolution,
    coil_rotary_inertia,
    deployed_fraction,
    deployment_time,
    deployment_time_lambda0,
    free_hub_factors,
    seffen_rate,
    solve_deployment_ode,
    stowed_rotary_inertia,
)
from tapecoil.theory.edge_layer import (
    EdgeLayer,
    coiling_tension_with_edges,
    edge_layer,
    fold_moment_with_edges,
)
from tapecoil.theory.laminate import Bending, Wall, plane_stress_stiffness, ply_stiffness
from tapecoil.theory.plate import (
    SENSES,
    arc_second_moment,
    coil_energy_at_R,
    coil_stresses,
    energy_density,
    flexural_rigidity,
    fold_moment,
    fold_radius,
    opposite_sense_energy_density,
    ploy_length,
    sense_sign,
)
from tapecoil.theory.table import Prediction, predictions

__all__ = [
    "SENSES",
    "UNIQUENESS_LIMIT",
    "Bending",
    "DeploymentSolution",
    "EdgeLayer",
    "Prediction",
    "Wall",
    "arc_second_moment",
    "coil_energy_at_R",
    "coil_radius_during_deployment",
    "coil_rotary_inertia",
    "coil_stresses",
    "coiled_length_from_radius",
    "coiled_length_from_rotation",
    "coiling_regime",
    "coiling_tension_bending",
    "coiling_tension_growing",
    "coiling_tension_tension_dominated",
    "coiling_tension_with_edges",
    "deployed_fraction",
    "deployment_time",
    "deployment_time_lambda0",
    "edge_layer",
    "energy_density",
    "flexural_rigidity",
    "fold_moment",
    "fold_moment_with_edges",
    "fold_radius",
    "free_hub_factors",
    "max_hub_angle",
    "opposite_sense_energy_density",
    "outer_radius_after_rotation",
    "plane_stress_stiffness",
    "ploy_length",
    "ply_stiffness",
    "predictions",
    "radius_from_coiled_length",
    "required_coiling_tension",
    "rotation_for_coiled_length",
    "seffen_rate",
    "sense_sign",
    "solve_deployment_ode",
    "stored_energy",
    "stowed_rotary_inertia",
    "turn_radius",
]

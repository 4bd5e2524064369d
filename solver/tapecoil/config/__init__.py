"""Run parameters: typed dataclasses in SI units, loaded from TOML and checked before any work.

The defaults are the benchmark tape of the physics brief (thesis Table 3.1, annealed BeCu) and
its loading (Table 3.2). Every field carries its unit and its allowed range in the field
metadata; :func:`load_config` refuses an unknown key, a wrong type or an out-of-range value
with a :class:`ConfigError` that names the key (``tape.h``) and what is allowed. It also
refuses a hub rotation longer than the tape can give, so that it is not found only after hours
of computing. A pull below the tension the hub needs is no error: :meth:`Config.coiling_warnings`
names it, and the commands that start a coiling warn of it (:class:`ConfigWarning`) before
computing; loading a configuration (for a report, a plot, a tension study) does not.

The package: :mod:`~tapecoil.config.params` (a field's unit and range, the checks of a value),
:mod:`~tapecoil.config.sections` (the dataclasses) and :mod:`~tapecoil.config.toml` (reading and
writing TOML).
"""

from tapecoil.config.laminate import LaminateConfig
from tapecoil.config.params import NON_NEGATIVE, POSITIVE, ConfigError, ConfigWarning, Range, param
from tapecoil.config.sections import (
    CoilingConfig,
    Config,
    ContactConfig,
    DeploymentConfig,
    HubConfig,
    MeshConfig,
    ModelConfig,
    OutputConfig,
    PayoutConfig,
    SolverConfig,
    StepControl,
    TapeConfig,
)
from tapecoil.config.toml import config_from_dict, load_config, to_toml

__all__ = [
    "NON_NEGATIVE",
    "POSITIVE",
    "CoilingConfig",
    "Config",
    "ConfigError",
    "ConfigWarning",
    "ContactConfig",
    "DeploymentConfig",
    "HubConfig",
    "LaminateConfig",
    "MeshConfig",
    "ModelConfig",
    "OutputConfig",
    "PayoutConfig",
    "Range",
    "SolverConfig",
    "StepControl",
    "TapeConfig",
    "config_from_dict",
    "load_config",
    "param",
    "to_toml",
]

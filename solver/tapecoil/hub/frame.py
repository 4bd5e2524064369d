"""Where the hub is: its axis relative to the tape's root."""

from __future__ import annotations

import numpy as np


def hub_axis_point(r_hub: float, h: float) -> np.ndarray:
    """A point of the hub axis (the axis runs along y): (0, 0, -(r_hub + h/2))."""
    return np.array([0.0, 0.0, -(r_hub + h / 2)])

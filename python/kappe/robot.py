"""UR10e kinematics and robot plans."""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from . import _kappe

__all__ = ["ik", "plan"]


def _mat4(m: Any, name: str) -> list:
    a = np.asarray(m, dtype=float)
    if a.shape != (4, 4):
        raise ValueError(f"{name}: expected a 4×4 matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: not finite")
    return a.tolist()


def ik(pose: Any, flange_from_tcp: Optional[Any] = None) -> np.ndarray:
    """Every inverse-kinematics solution (k×6 joint angles, rad) of a 4×4 TCP pose."""
    tool = None if flange_from_tcp is None else _mat4(flange_from_tcp, "flange_from_tcp")
    sols = _kappe.robot_ik(_mat4(pose, "pose"), tool)
    return np.asarray(sols, dtype=float).reshape(-1, 6)


def plan(design: Any = None, **kwargs: Any):
    """The robot plan of a design: :func:`kappe.design` with the robot (no analysis unless
    ``analysis=`` is given); its ``trajectory`` holds time and joints."""
    from . import design as run_design

    kwargs.setdefault("analysis", None)
    return run_design(design, robot=True, **kwargs)

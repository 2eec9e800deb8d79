"""Force capability of mechanisms: pure functions of Jacobians and actuator limits, workspace maps,
their statistics and convergence. numpy/scipy only.

The public face, so scripts and notebooks need no private module:

>>> import numpy as np
>>> from metrics import condition_number, isotropic_force
>>> float(condition_number(np.eye(3)))
1.0
>>> float(isotropic_force(np.eye(3), torque_limits=[2.0, 3.0, 4.0]))
2.0

Design studies (culling and count searches, local or Dask) are the subpackage ``metrics.design``.

Each public name is imported from its module on first use (PEP 562 ``__getattr__``): importing
one module of the package (``metrics.dextrous`` for ``isoforce dextrous``) then costs that module
and what it imports, not every module listed here (0.3 s of CPU when they were imported eagerly).
"""
from __future__ import annotations

from kinematics.lazy import public_names

#: Module of this package -> the public names it gives the package.
# ``metrics.gii.gii`` is not lifted here: the module ``metrics.gii`` keeps its name.
_PUBLIC = {
    "conditioning": ("condition_number", "manipulability"),
    "convergence": ("ConvergenceStudy", "convergence_study"),
    "refine": ("refine_global_maximum", "refine_global_minimum"),
    "ellipsoids": ("Ellipsoid", "force_ellipsoid", "force_ellipsoid_min_radius", "velocity_ellipsoid"),
    "gii": ("GIIResult", "local_isotropy"),
    "bottleneck": ("BOTTLENECK_INFEASIBLE", "BOTTLENECK_SHARED", "BOTTLENECK_TIE", "bottleneck_actuator"),
    "anisotropy": ("anisotropic_force",),
    "columns": ("column_norms",),
    "isotropy": ("clamp_force", "facet_distances", "isotropic_force"),
    "parallelepiped": ("polytope_vertices", "reference_forces"),
    "zonotopes": ("Zonotope", "zonotope", "zonotope_vertices"),
    "pose": ("PoseReport", "analyse_pose"),
    "quantities": ("CORE_QUANTITIES", "MAP_QUANTITIES", "QUANTITIES", "STATS_QUANTITIES", "evaluate"),
    "workspace": ("GridSpec", "Stats", "WorkspaceMap", "compute_map", "resolution_error"),
    "wrench_facets": ("slice_inscribed_radius",),
    "wrench_slices": ("slice_max_norm",),
    "pose_velocity": ("analyse_pose_velocity",),
    "velocity": ("PoseVelocity", "analyse_velocity", "isotropic_velocity", "joint_speed_limits", "peak_velocities",
                 "rate_slab_radius", "velocity_polytope", "velocity_polytope_vertices"),
}
_HOME = {name: module for module, names in _PUBLIC.items() for name in names}

__all__ = list(_HOME)


__getattr__, __dir__ = public_names(__name__, _HOME)

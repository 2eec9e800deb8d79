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
"""
from .anisotropy import anisotropic_force
from .bottleneck import BOTTLENECK_INFEASIBLE, BOTTLENECK_SHARED, BOTTLENECK_TIE, bottleneck_actuator
from .columns import column_norms
from .conditioning import condition_number, manipulability
from .convergence import ConvergenceStudy, convergence_study
from .ellipsoids import Ellipsoid, force_ellipsoid, force_ellipsoid_min_radius, velocity_ellipsoid

# ``metrics.gii.gii`` is not lifted here: the module ``metrics.gii`` keeps its name.
from .gii import GIIResult, local_isotropy
from .isotropy import clamp_force, facet_distances, isotropic_force
from .parallelepiped import polytope_vertices, reference_forces
from .pose import PoseReport, analyse_pose
from .pose_velocity import analyse_pose_velocity
from .quantities import CORE_QUANTITIES, MAP_QUANTITIES, QUANTITIES, STATS_QUANTITIES, evaluate
from .refine import refine_global_maximum, refine_global_minimum
from .velocity import (
    PoseVelocity,
    analyse_velocity,
    isotropic_velocity,
    joint_speed_limits,
    peak_velocities,
    rate_slab_radius,
    velocity_polytope,
    velocity_polytope_vertices,
)
from .workspace import GridSpec, Stats, WorkspaceMap, compute_map, resolution_error
from .wrench_facets import slice_inscribed_radius
from .wrench_slices import slice_max_norm
from .zonotopes import Zonotope, zonotope, zonotope_vertices

__all__ = [
    "condition_number", "manipulability",
    "ConvergenceStudy", "convergence_study", "refine_global_maximum", "refine_global_minimum",
    "Ellipsoid", "force_ellipsoid", "force_ellipsoid_min_radius", "velocity_ellipsoid",
    "GIIResult", "local_isotropy",
    "BOTTLENECK_INFEASIBLE", "BOTTLENECK_SHARED", "BOTTLENECK_TIE", "Zonotope", "anisotropic_force",
    "bottleneck_actuator", "clamp_force", "column_norms", "facet_distances", "isotropic_force",
    "polytope_vertices", "reference_forces", "zonotope", "zonotope_vertices",
    "PoseReport", "analyse_pose",
    "CORE_QUANTITIES", "MAP_QUANTITIES", "QUANTITIES", "STATS_QUANTITIES", "evaluate",
    "GridSpec", "Stats", "WorkspaceMap", "compute_map", "resolution_error",
    "slice_inscribed_radius", "slice_max_norm",
    "PoseVelocity", "analyse_pose_velocity", "analyse_velocity", "isotropic_velocity", "joint_speed_limits",
    "peak_velocities", "rate_slab_radius", "velocity_polytope", "velocity_polytope_vertices",
]

"""Force polytopes, the map: which module computes what, with the equations in one place.

For a square Jacobian the forces the device holds with ``|tau_u| <= t_u`` form the
parallelepiped ``P = {f : |J[:, u] . f| <= t_u}`` (paper 000 sec. 2). Its vertices are
``J^-T (+-t_1, ..., +-t_n)``; the columns of ``R = J^-T diag(t)`` are the paper's reference
forces (eq. 3-6).

=========================  ============================================  ======================
quantity                   how we compute it                             paper 000
=========================  ============================================  ======================
isotropic force            min_u t_u / |J[:, u]|: the distance from 0    eq. 7-8 (same value,
                           to facet u, no inverse, finite at             no cross products of
                           singularities                                 reference forces)
bottleneck actuator        argmin of the same                            --
anisotropic force          max vertex norm, vertices from J^-T           eq. 6
force clamp                F_d scaled down to the isotropic radius       eq. 9
=========================  ============================================  ======================

With redundant actuation (``f = A tau`` with ``A`` of shape (m, n), n > m) the force set
is the zonotope ``A [-t, t]^n``: ``metrics.zonotopes`` handles it.

Asymmetric limits and a torque bias (``torque_min=``, default ``-torque_limits``;
``torque_bias=``, default 0; as in pycapacity's ``force_polytope(J, t_max, t_min, t_bias)``
the bias is torque the joints already spend) leave the usable range
``lo = torque_min - b <= tau <= hi = torque_limits - b`` (``torque_range``). The force set
is then a shifted parallelepiped ``{f : lo <= J^T f <= hi}`` or zonotope ``A [lo, hi]``:

=========================  ============================================  ======================
quantity                   how we compute it (lo, hi)                    symmetric case
=========================  ============================================  ======================
facet distances            min(hi_u, -lo_u) / |J[:, u]|, signed:         t_u / |J[:, u]|
                           negative where 0 is outside slab u
isotropic force            max(0, min_u of the same): distance from 0    min_u t_u / |J[:, u]|
                           to the nearest facet, 0 outside the set
bottleneck actuator        argmin of the same, clipped at 0 (every       same
                           actuator that excludes 0 ties)
reference forces           half-edges J^-T diag((hi - lo) / 2) about     J^-T diag(t)
                           the centre J^-T (hi + lo) / 2
                           (``polytope_centre``)
vertices                   J^-T v, v_u = hi_u (s_u = +1) or lo_u         J^-T diag(t) s
anisotropic force          max vertex norm (all 2^n, no +- symmetry)     max over half
zonotope facets            +-nu_k, offsets H_k +- nu_k . A (hi + lo)/2,  H_k = sum_u t_u
                           H_k = sum_u (hi - lo)_u / 2 |A_u . nu_k|      |A_u . nu_k|
=========================  ============================================  ======================

Where neither ``torque_min`` nor ``torque_bias`` is given, or the range comes out centred
(``lo == -hi`` everywhere), the symmetric code runs unchanged (bit-identical numbers).

The code lives in modules that answer one question each; this one holds no code, only the
tables above and the one below, and the names of those modules re-exported so that
``metrics.polytopes.isotropic_force`` and the like keep working. Code in this repository
imports each name from the module that defines it.

==========================  ===========================================================================
module                      what it answers
==========================  ===========================================================================
``metrics.torque_box``      the box of joint torques: corners (``sign_patterns``), usable range
                            (``torque_range``, ``asymmetric_range``)
``metrics.columns``         Jacobian column norms safe from over- and underflow (``column_norms``),
                            columns at rounding level (``negligible_columns``)
``metrics.parallelepiped``  the parallelepiped itself: ``reference_forces``, ``polytope_centre``,
                            ``polytope_vertices``, ``parallelepiped_faces`` (and ``shifted_vertices``,
                            ``matvecs``)
``metrics.isotropy``        the nearest facet: ``facet_distances``, ``isotropic_force``, eq. 7-8 as
                            printed (``isotropic_force_cross_product``), the clamp (``clamp_force``)
``metrics.bottleneck``      which actuator is nearest: ``bottleneck_actuator``,
                            ``bottleneck_of_distances``, ``tie_tolerance``, the ``BOTTLENECK_*`` codes
``metrics.anisotropy``      the farthest vertex: ``anisotropic_force``
``metrics.zonotopes``       redundant actuation (n > m): ``zonotope``, ``zonotope_vertices``
==========================  ===========================================================================
"""
from .anisotropy import anisotropic_force
from .bottleneck import (
    BOTTLENECK_INFEASIBLE,
    BOTTLENECK_SHARED,
    BOTTLENECK_TIE,
    bottleneck_actuator,
    bottleneck_of_distances,
    tie_tolerance,
)
from .columns import column_norms, negligible_columns
from .isotropy import clamp_force, facet_distances, isotropic_force, isotropic_force_cross_product
from .parallelepiped import matvecs, parallelepiped_faces, polytope_centre, polytope_vertices, reference_forces
from .torque_box import asymmetric_range, sign_patterns, torque_range

__all__ = [
    "BOTTLENECK_INFEASIBLE", "BOTTLENECK_SHARED", "BOTTLENECK_TIE",
    "anisotropic_force", "asymmetric_range", "bottleneck_actuator", "bottleneck_of_distances", "clamp_force",
    "column_norms", "facet_distances", "isotropic_force", "isotropic_force_cross_product", "matvecs",
    "negligible_columns", "parallelepiped_faces", "polytope_centre", "polytope_vertices", "reference_forces",
    "sign_patterns", "tie_tolerance", "torque_range",
]

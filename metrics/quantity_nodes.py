"""How each node of the quantity graph (``metrics.quantities``) computes, from the values of its inputs.

Every function takes ``v``, the values computed so far (``joints``, ``jacobian``, ``torques``:
the loading's ``TorqueSet``, built once at the entry of a pose or a map and shifted by the
``torque_bias`` node's value with gravity on...), and the mechanism; the table in
``metrics.quantities`` names which node calls which and what it needs.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from kinematics.arrays import FloatArray
from kinematics.contract import Mechanism

from . import (
    anisotropy,
    biased_sections,
    bottleneck,
    dynamics,
    torque_box,
    velocity,
    wrench_facets,
    wrench_slices,
    wrenches,
    zonotopes,
)
from .loading import DEFAULT_LOADING, Loading
from .torque_box import TorqueSet


def loading_of(values: dict[str, Any]) -> Loading:
    """The ``Loading`` an evaluation runs under (``values["loading"]``; ``DEFAULT_LOADING`` if absent).

    Parameters
    ----------
    values : dict
        The graph's values.

    Returns
    -------
    Loading
    """
    return values.get("loading") or DEFAULT_LOADING


def torques_of(v: dict[str, Any], mech) -> TorqueSet:
    """The evaluation's torque set (``v["torques"]``), taken as it is by every force node.

    Values built without an entry (no ``"torques"``) get the loading's set, biased by
    ``v["torque_bias"]`` once that is computed: the set the entry builds.
    """
    box = v.get("torques")
    if box is None:
        loading = loading_of(v)
        box = loading.torque_set(mech)
        if loading.biased and "torque_bias" in v:
            box = box.with_bias(v["torque_bias"])
    return box


def add_bias(v: dict[str, Any]) -> None:
    """Shift ``v["torques"]`` by the ``torque_bias`` just computed (gravity on); run once, after that node."""
    if loading_of(v).biased and "torques" in v:
        v["torques"] = v["torques"].with_bias(v["torque_bias"])


def rated_limits(v: dict[str, Any], mech) -> FloatArray:
    """The rated joint torque limits (n,) of the evaluation's loading, N m."""
    return torques_of(v, mech).limits


def bias_of(v: dict[str, Any], mech) -> FloatArray | None:
    """The per-pose torque bias (k, n), N m, or ``None`` with gravity off (the symmetric code path)."""
    return torques_of(v, mech).bias


def slab_shifts(v: dict[str, Any], mech, packed: FloatArray) -> FloatArray | None:
    """Where each slab of the biased wrench set is centred, ``nu . c`` (k, S); ``None`` with gravity off.

    With a torque bias ``b`` the set ``{A tau : -t - b <= tau <= t - b}`` is ``c + W``, ``c = -A b``.
    Square J (slabs ``nu_u = J[:, u]``, ``A = J^-T``): ``nu_u . c = -b_u`` exactly, no inverse. A
    redundant model: ``c = -A b`` from its generators ``A diag(t)`` (``reference_forces``).
    """
    box = torques_of(v, mech)
    if box.bias is None:
        return None
    if not mech.is_redundant:
        return -box.bias
    centre = -np.einsum("kmn,kn->km", v["reference_forces"], box.per_unit.bias)
    return wrench_facets.slab_shifts(packed[..., :-1], centre)


def wrench_radius(v: dict[str, Any], mech, rows) -> FloatArray:
    """Inscribed radius of the (biased, with gravity on) wrench set's slice on ``rows``."""
    packed = v["wrench_facets"]
    return wrench_facets.slice_inscribed_radius(packed[..., :-1], slab_offsets(v, packed), rows=rows,
                                                shifts=slab_shifts(v, mech, packed))


def slab_offsets(v: dict[str, Any], packed: FloatArray) -> FloatArray:
    """The slabs' offsets ``h`` (k, S) of ``packed``, contiguous, formed once per evaluation.

    ``slice_inscribed_radius``'s kernel takes them contiguous: the packed column, a strided view,
    was copied for each slice (force and moment), 4 ms a chunk of 25,000 Twin-Pantograph points.
    """
    kept = v.get("_slab_offsets")
    if kept is None or kept[0] is not packed:
        kept = v["_slab_offsets"] = (packed, np.ascontiguousarray(packed[..., -1]))
    return kept[1]


def wrench_bottleneck(v: dict[str, Any], mech) -> np.ndarray:
    """The actuator nearest the origin in the zero-moment force set; shared where actuation is redundant.

    With a bias actuator u's slab is ``-t_u - b_u <= J[:, u] . w <= t_u - b_u``: its nearer face is
    ``(t_u - |b_u|) / |J[rows, u]|`` away.
    """
    if mech.is_redundant:
        return np.full(len(v["joints"]), bottleneck.BOTTLENECK_SHARED)
    return bottleneck.bottleneck_of_distances(wrench_facets.slice_facet_distances(
        v["jacobian"], torque_limits=torques_of(v, mech).nearer, rows=wrenches.force_rows(mech)))


def generators(v: dict[str, Any], mech) -> FloatArray:
    """``A diag(t)`` (..., m, n): each actuator's wrench at full (rated) torque."""
    rows = twin_rows(v, mech)
    force_map = mech.force_map(v["joints"], v["pose"]) if rows is None else np.swapaxes(rows[0], -1, -2)
    return force_map * rated_limits(v, mech)


def contiguous_generators(v: dict[str, Any]) -> FloatArray:
    """``reference_forces`` C-contiguous, copied once per evaluation for the compiled readers.

    The Twin-Pantograph's generators are ``K^T`` (a transposed view) times the limits, in that
    layout; the two slices' largest norms, the slabs and ``lost_poses`` each made a C copy of
    them (numpy's own products, ``einsum`` of ``slab_shifts``, keep the original: their sums'
    order follows the layout). The same values, in one copy.
    """
    gen = v["reference_forces"]
    kept = v.get("_contiguous_generators")
    if kept is None or kept[0] is not gen:
        kept = v["_contiguous_generators"] = (gen, np.ascontiguousarray(gen, dtype=np.float64))
    return kept[1]


def twin_rows(v: dict[str, Any], mech) -> tuple[FloatArray, FloatArray | None] | None:
    """``K`` (k, n, 5) and ``J`` (k, 5, n) of a 5-DOF Twin-Pantograph at ``v``'s poses, compiled once
    per evaluation (``kernels.twin_rows``); ``None`` for any other model (the model's own).

    ``J`` is ``None`` with five actuators (the model's ``jacobian``, an inverse, is taken); at a
    pose the kernel hands back (a Gram matrix too ill-conditioned for its Cholesky) it is the
    model's ``jacobian``, as ``kinematics.rotations.spd_inverse`` hands it to ``batched_inverse``.
    """
    from .kernels import registered_kind

    if registered_kind(mech) != "twin_pantograph":          # no numba import for the other models
        return None
    if "_twin_rows" not in v:
        from .kernels import twin_rows as kernel

        if not kernel.supports(mech):
            v["_twin_rows"] = None
            return None
        x = np.ascontiguousarray(v["pose"], dtype=np.float64)
        n = mech.n_joints
        k = np.empty((len(x), n, 5))
        jac = np.empty((len(x), 5, n)) if n == 6 else None
        handed = np.zeros(len(x), bool)
        kernel.jacobians(x, kernel.pack(mech), np.array(mech.actuated, np.int64), k,
                         jac if jac is not None else np.empty((0, 5, n)), handed)
        if jac is not None and handed.any():
            jac[handed] = mech.jacobian(v["joints"][handed], x[handed])
        v["_twin_rows"] = (k, jac)
    return v["_twin_rows"]


def anisotropic(v: dict[str, Any], mech) -> FloatArray:
    """Largest vertex norm of the (shifted, with a bias) parallelepiped."""
    box = torques_of(v, mech)
    ref = None if box.shifted else v["reference_forces"]
    return anisotropy.anisotropic_force(v["jacobian"], ref=ref, torque_limits=box)


def redundant_anisotropic(v: dict[str, Any], mech) -> FloatArray:
    """Largest vertex norm of the (shifted, with a bias) zonotope ``A diag(t) [-1 - b/t, 1 - b/t]^n``."""
    box = torques_of(v, mech).per_unit
    if box.bias is None:
        return zonotope_max_norm(v["reference_forces"])
    verts = zonotopes.zonotope_vertices(v["reference_forces"], torque_limits=box)
    return np.sqrt(np.max(np.sum(verts * verts, axis=-1), axis=-1))


def torque_bias(v: dict[str, Any], mech) -> FloatArray:
    """The gravity torque at each pose (k, n), N m; zeros with gravity off."""
    b = loading_of(v).torque_bias(mech, v["joints"])
    return np.zeros(np.shape(v["joints"])) if b is None else b


def zonotope_max_norm(gen: FloatArray) -> FloatArray:
    """Largest norm over the zonotope: attained at a vertex, i.e. at one of the signed sums."""
    sums = np.einsum("...ij,kj->...ki", gen, torque_box.sign_patterns(gen.shape[-1], half=True))
    return np.sqrt(np.max(np.sum(sums * sums, axis=-1), axis=-1))


def square_facets(jac: FloatArray, t: FloatArray) -> FloatArray:
    """Square J (tau = J^T w): slabs ``|J[:, u] . w| <= t_u``, packed (..., n, m + 1)."""
    normals = np.swapaxes(jac, -1, -2)
    return np.concatenate([normals, np.broadcast_to(t[:, None], normals.shape[:-1] + (1,))], -1)


def unbounded_where_lost(out: FloatArray, jac: FloatArray, force_map: FloatArray) -> FloatArray:
    """``inf`` where a redundant model's pose is singular to machine precision, ``out`` elsewhere.

    A unit's leg stretched or folded makes its joint rates divide by (nearly) zero: J is not
    finite there, or J is ~1e-15 and the force map ``A`` (..., m, n) ~1e17, rounding noise rather
    than a force (the Twin-Pantograph's map meets such poses near z = 45 mm, both legs
    stretched). A consistent pair has ``J A^T = I`` to within rounding, at most about
    ``64 n eps |J|_F |A|_F``; where the residual is larger (here of order 1) or not finite, the
    pose is singular, and the largest norm of the set is unbounded in truth, as at the
    five-bar's inverse singularities: ``inf``.
    """
    m, n = force_map.shape[-2:]
    with np.errstate(over="ignore", invalid="ignore"):
        # np.matmul, not einsum: the same n-term sums, a fraction of einsum's generic loop's time.
        residual = np.max(np.abs(np.matmul(jac, np.swapaxes(force_map, -1, -2)) - np.eye(m)), axis=(-2, -1))
        bound = 64 * n * np.finfo(float).eps * np.linalg.norm(jac, axis=(-2, -1)) * np.linalg.norm(force_map,
                                                                                                 axis=(-2, -1))
    lost = ~(residual <= bound)
    return np.where(lost, np.inf, out) if np.any(lost) else out


def lost_poses(v: dict[str, Any], mech) -> np.ndarray:
    """Where a redundant model's pose is singular to machine precision (``unbounded_where_lost``), (k,).

    Computed once per evaluation (kept in ``v`` under ``"_lost"``): the anisotropic force and
    moment both ask for it at the same poses.
    """
    if "_lost" not in v:
        rows = twin_rows(v, mech)
        if rows is not None and rows[1] is not None and len(v["jacobian"]):
            # The Twin-Pantograph's J (``twin_rows``): the same test compiled (``kernels.twin_nodes``);
            # a residual within rounding of its bound, or anything not finite, decided here.
            from .kernels import twin_nodes

            gen = v["reference_forces"]
            t = np.ascontiguousarray(rated_limits(v, mech), dtype=np.float64)
            lost, undecided = np.empty(len(gen), bool), np.empty(len(gen), bool)
            twin_nodes.lost_points(np.ascontiguousarray(v["jacobian"]), contiguous_generators(v), t, lost,
                                   undecided)
            if np.any(undecided):
                lost[undecided] = np.isinf(unbounded_where_lost(
                    np.zeros(int(undecided.sum())), v["jacobian"][undecided], gen[undecided] / t))
            v["_lost"] = lost
        else:
            lost = unbounded_where_lost(np.zeros(len(v["jacobian"])), v["jacobian"],
                                        v["reference_forces"] / rated_limits(v, mech))
            v["_lost"] = np.isinf(lost)
    return v["_lost"]


def wrench_slice_max(v: dict[str, Any], mech, rows) -> FloatArray:
    """Largest norm of a wrench set's slice on ``rows`` (forces at zero moment, or moments at zero force).

    From the generators ``A diag(t)`` (``wrench_slices.slice_max_norm``), except where a square J has an
    exactly zero column (an actuator at an inverse singularity, ``kinematics.base.singular_limit``):
    there ``A = J^-T`` does not exist (its column is 1e17 noise or inf) while the slice is still
    bounded by the other slabs, and ``wrench_facets.slab_slice_max_norm`` takes it from them.
    """
    jac = v["jacobian"]
    if bias_of(v, mech) is not None and len(jac):
        return biased_slice_max(v, mech, rows)
    out = wrench_slices.slice_max_norm(contiguous_generators(v), rows=rows)
    if not len(jac):
        return out
    if mech.is_redundant:
        return np.where(lost_poses(v, mech), np.inf, out)
    singular = np.all(np.isfinite(jac), axis=(-2, -1)) & np.any(np.all(jac == 0, axis=-2), axis=-1)
    if np.any(singular):
        out = np.array(out, float)
        out[singular] = wrench_facets.slab_slice_max_norm(jac[singular], torque_limits=rated_limits(v, mech), rows=rows)
    return out


def needs_singularity(mech: Mechanism) -> bool:
    return bool(mech.singularity_classes)


def scaled_condition(v: dict[str, Any], mech) -> FloatArray:
    """The wrench devices' ``condition_number``: ``wrenches.scaled_condition_number`` of ``J``.

    The redundant 5-DOF Twin-Pantograph's (``twin_rows`` has its ``J``): the scaled ``M = S_T J``'s
    Gram matrix ``M M^T`` formed as ``linalg._sv_gram`` forms it (the same bits), its extreme
    eigenvalues by ``kernels.twin_batch.extremes`` (cyclic Jacobi, 8 lanes, a derived bound in
    its module doc) instead of LAPACK's ``eigvalsh``, ``kappa = sqrt(lambda_max / lambda_min)``.
    A point ``_sv_gram`` would send to LAPACK's SVD (``kappa`` beyond ``FAST_COND_LIMIT``, entries
    outside ``SAFE_SCALE``, not finite) or whose Jacobi met its cap takes the numpy path.
    """
    jac = v["jacobian"]
    scale = wrenches.task_row_scale(mech)
    rows = twin_rows(v, mech)
    if rows is None or rows[1] is None or not len(jac):
        return wrenches.scaled_condition_number(jac, row_scale=scale)
    from .kernels import twin_batch, twin_nodes
    from .linalg import FAST_COND_LIMIT, SAFE_SCALE

    # M M^T where M is finite and within SAFE_SCALE (``good``), zeros elsewhere, as
    # ``np.where(good, M, 0) @ M^T`` gives it (``kernels.twin_nodes.scaled_gram``: matmul's sums).
    gram = np.empty((len(jac),) + jac.shape[-2:-1] * 2)
    good = np.empty(len(jac), bool)
    twin_nodes.scaled_gram(np.ascontiguousarray(jac, dtype=np.float64), np.ascontiguousarray(scale, dtype=np.float64),
                           *SAFE_SCALE, gram, good)
    ext = np.empty((len(gram), 2))
    count = np.empty(len(gram), np.int64)
    twin_batch.extremes(gram, ext, count, np.empty(len(gram), np.int64), twin_batch.lane_buffer()[0])
    with np.errstate(invalid="ignore", divide="ignore"):
        low, high = np.sqrt(np.maximum(ext[:, 0], 0.0)), np.sqrt(ext[:, 1])
        cond = high / low
        hard = ~good | ~(high <= FAST_COND_LIMIT * low)       # nan (the cap) is hard too
    if np.any(hard):
        cond[hard] = wrenches.scaled_condition_number(jac[hard], row_scale=scale)
    return cond


def jacobian_at_pose(v: dict[str, Any], mech) -> FloatArray:
    """J at the requested pose. The five-bar's J depends on the assembly as well as on q, and
    ``forward(q)`` in the configured assembly can be the other one (e.g. below the base line),
    so every mechanism's ``jacobian`` gets the pose ``x`` (the contract: ``jacobian(q, x=None)``).
    The redundant 5-DOF Twin-Pantograph's is compiled (``twin_rows``)."""
    rows = twin_rows(v, mech)
    if rows is not None and rows[1] is not None:
        return rows[1]
    return mech.jacobian(v["joints"], v["pose"])


def inertias(v: dict[str, Any], mech) -> FloatArray:
    """``Lambda`` and ``Lambda^-1`` (k, 2, m, m): each from where it is finite.

    Joint-placed models (``mass_coordinates = "joint"``) give ``M``, so the mobility
    ``J M^-1 J^T`` is finite at an inverse singularity and ``Lambda`` is its inverse (``inf``
    along the locked direction); task-placed ones give ``Lambda`` directly.
    """
    q, x = v["joints"], v["pose"]
    if not len(q):
        return np.zeros((0, 2, mech.task_dim, mech.task_dim))
    if mech.mass_coordinates == "joint":
        mob = dynamics.mobility(v["jacobian"], mech.mass_matrix(q, x))
        lam = dynamics.inverse_spd(mob)
    else:
        lam = dynamics.task_inertia(mech, q, x)
        mob = dynamics.inverse_spd(lam)
        # At a pose the model classes an inverse singularity (a leg stretched or folded) the
        # device cannot move along some direction: its joint rates per task rate are unbounded.
        # Lambda is marked infinite there (the heaviest apparent mass unbounded, the acceleration
        # set flat) and the mobility unknown (nan), the singular limit the force quantities take
        # at the same poses (the model's J has that column exactly 0 within its tolerance);
        # likewise any other singular pose whose Lambda is not finite.
        if mech.singularity_classes:
            code = mech.singularity(q, x)
            locked = [i for i, name in enumerate(mech.singularity_classes) if name in ("inverse", "combined")]
            lost = np.isin(code, locked) | (~np.all(np.isfinite(lam), axis=(-2, -1)) & (code != 0))
            lam[lost], mob[lost] = np.inf, np.nan
    return np.stack([lam, mob], axis=1)


def singular_marked(v: dict[str, Any]) -> np.ndarray:
    """Poses whose Lambda ``inertias`` marked infinite (a singular pose of a task-placed model)."""
    lam = v["mass_matrices"][:, 0]
    # Only a pose whose first entry is +inf can be marked: the whole test runs on those alone (a
    # pass over every entry took 1-7 ms a chunk of 25,000 Twin-Pantograph poses, with the load).
    marked = np.isposinf(lam[:, 0, 0])
    some = np.flatnonzero(marked)
    if len(some):
        marked[some] = np.all(np.isposinf(lam[some]), axis=(-2, -1))
    return marked


def mass_range(v: dict[str, Any], mech) -> FloatArray:
    """Lightest and heaviest apparent mass (k, 2), one eigen-decomposition for both and the condition."""
    mob, rows = v["mass_matrices"][:, 1], list(wrenches.force_rows(mech))
    if rows and rows == list(range(rows[0], rows[0] + len(rows))):
        # Consecutive rows (a pen's or a platform's forces) as a view: the same entries as
        # ``apparent_mass_range``'s two fancy-indexed copies, which took 9.5 of its 16 ms on a chunk of
        # 25,000 Twin-Pantograph mobilities.
        mob, rows = mob[:, rows[0]:rows[-1] + 1, rows[0]:rows[-1] + 1], None
    out = dynamics.apparent_mass_range(mob, rows)
    out[:, 1] = np.where(singular_marked(v), np.inf, out[:, 1])
    return out


def acceleration_slabs(v: dict[str, Any], mech, packed: FloatArray) -> FloatArray:
    """Inscribed radius at zero angular acceleration of the acceleration set of the slabs ``packed``.

    The set ``{a : Lambda a in c + W}``: slab k is ``|(Lambda nu_k) . a - nu_k . c| <= h_k``, the same
    shifts as the (biased) wrench set's.
    """
    lam = v["mass_matrices"][:, 0]
    rows = wrenches.force_rows(mech)
    shifts = slab_shifts(v, mech, packed)
    if shifts is None and 1 <= len(rows) <= 3 and len(lam) and packed.ndim == 3:
        # Gravity off: the radius from the slabs and Lambda point by point (``kernels.facets``), no
        # (k, S, m) normals; a point it leaves (Lambda not finite, a normal out of range) as below.
        from .kernels import facets

        h = np.ascontiguousarray(packed[..., -1])
        out, redo = np.empty(len(lam)), np.empty(len(lam), bool)
        facets.acceleration_radius_points(packed[..., :-1], h, lam, np.array(rows, np.int64) % lam.shape[-1], out,
                                          redo)
        if np.any(redo):
            with np.errstate(invalid="ignore"):
                normals = dynamics.acceleration_facets(packed[redo][..., :-1], lam[redo])
                out[redo] = wrench_facets.slice_inscribed_radius(normals, h[redo], rows=rows)
        return out
    normals = dynamics.acceleration_facets(packed[..., :-1], lam)
    with np.errstate(invalid="ignore"):
        return wrench_facets.slice_inscribed_radius(normals, packed[..., -1], rows=rows, shifts=shifts)


def weight(v: dict[str, Any], mech) -> FloatArray:
    """Norm of the force (force rows) a hand holds against gravity, N; upright when gravity is off."""
    from kinematics.dynamics import task_gravity_force
    from kinematics.gravity import gravity_vector
    loading = loading_of(v)
    g = loading.gravity if loading.biased else gravity_vector("upright")
    if not len(v["joints"]):
        return np.zeros(0)
    force = task_gravity_force(mech, v["joints"], v["pose"], g)[..., list(wrenches.force_rows(mech))]
    # Scaled before squaring: masses of 1e-300 or 1e300 kg give a weight that squares out of range.
    scale = np.max(np.abs(force), axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = force / np.where(scale > 0, scale, 1.0)[..., None]
    return scale * np.sqrt(np.sum(unit * unit, axis=-1))


def biased_wrench_slabs(v: dict[str, Any], mech) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The gravity-biased wrench set as slabs ``lo <= nu . w <= hi``: ``nu`` (k, S, m), ``lo``, ``hi`` (k, S).

    Square J: slabs ``J[:, u]``, ``-t_u - b_u <= J[:, u] . w <= t_u - b_u``. Redundant: the
    zonotope's slabs (``wrench_facets.packed_facets``) about their shifted centres ``nu . c``.
    ``v`` holds the graph's ``jacobian``, ``reference_forces``, ``torque_bias`` and ``loading``
    (gravity on).
    """
    if mech.is_redundant:
        packed = wrench_facets.packed_facets(v["reference_forces"])
    else:
        packed = square_facets(v["jacobian"], rated_limits(v, mech))
    s = slab_shifts(v, mech, packed)
    return packed[..., :-1], s - packed[..., -1], s + packed[..., -1]


def biased_slice_max(v: dict[str, Any], mech, rows) -> FloatArray:
    """Largest norm of the biased wrench set's slice on ``rows``.

    Square J: the vertices of its slabs. Redundant: the section's vertices
    (``biased_sections.biased_slice_max_norm``, ``C(n, r) 2^(n - r)`` candidates a point), and
    the slabs' at the points it hands back (``biased_redundant_slabs_max``).
    """
    if not mech.is_redundant:
        nu, lo, hi = biased_wrench_slabs(v, mech)
        return wrench_facets.slab_slice_vertex_max_norm(nu, lo, hi, rows=rows)
    gen = v["reference_forces"]
    out, decided = biased_sections.biased_slice_max_norm(gen, torques_of(v, mech).per_unit.bias, rows=rows)
    if not np.all(decided):
        back = ~decided
        out[back] = biased_redundant_slabs_max(v, mech, rows, back)
    return unbounded_where_lost(out, v["jacobian"], gen / rated_limits(v, mech))


def biased_redundant_slabs_max(v: dict[str, Any], mech, rows, where: np.ndarray) -> FloatArray:
    """``slab_slice_vertex_max_norm`` of a redundant model's biased slabs at the poses ``where`` (k,) only.

    The slabs of ``biased_wrench_slabs`` (``packed_facets`` about the centres ``nu . c``,
    ``c = -A b``), built for those poses alone.
    """
    gen = v["reference_forces"][where]
    packed = wrench_facets.packed_facets(gen)
    beta = np.broadcast_to(torques_of(v, mech).per_unit.bias, v["reference_forces"].shape[:-2] + gen.shape[-1:])
    s = wrench_facets.slab_shifts(packed[..., :-1], -np.einsum("kmn,kn->km", gen, beta[where]))
    return wrench_facets.slab_slice_vertex_max_norm(packed[..., :-1], s - packed[..., -1], s + packed[..., -1],
                                                    rows=rows)


def gravity_torque_at_pose(v: dict[str, Any], mech) -> FloatArray:
    """The gravity torque (k, n) of a task-placed model with orientation freedoms: ``J^T w``.

    ``w = -sum_b m_b (dc_b/dxi)^T g`` (``kinematics.dynamics.task_gravity_force``, per twist) is the
    wrench gravity puts on the handle; ``J^T`` of it is the joints' torque (a redundant model's
    ``J = K^+``: the least-norm torques that hold it, ``A J^T = I``). From the pose, so a model
    whose forward kinematics is iterative (Inoue) needs none. Zeros with gravity off.
    """
    loading = loading_of(v)
    if not loading.biased:
        return np.zeros(np.shape(v["joints"]))
    from kinematics.dynamics import task_gravity_force
    if not len(v["joints"]):
        return np.zeros(np.shape(v["joints"]))
    wrench = task_gravity_force(mech, v["joints"], v["pose"], loading.gravity)
    with np.errstate(invalid="ignore", over="ignore"):
        return np.einsum("kmn,km->kn", v["jacobian"], wrench)


def no_speeds(mech) -> ValueError:
    """Why a velocity quantity is refused: the model's motor speeds are not given."""
    return ValueError(f"{type(mech).__name__} has no motor speeds (a preset's [motors] max_speeds, rad/s at the "
                      f"motor): no velocity polytope, isotropic or peak velocity")


def speed_limits_of(mech) -> FloatArray:
    """The joint speed limits ``motor_speeds / gear_ratios`` (n,), or the reason there are none."""
    speeds = mech.joint_speed_limits()
    if speeds is None:
        raise no_speeds(mech)
    return speeds


def joint_rates(v: dict[str, Any], mech, rows=slice(None)) -> FloatArray:
    """``K = dq/dx`` (k, n, m) of the poses ``rows``: the force map transposed (``w = A tau``, ``qdot = A^T xdot``)."""
    return np.swapaxes(mech.force_map(v["joints"][rows], v["pose"][rows]), -1, -2)


def velocity_radius(v: dict[str, Any], mech) -> FloatArray:
    """The velocity polytope's inscribed radius (k,), m/s (``metrics.velocity``).

    A square model without orientation freedoms: the zonotope ``J [-qdot_max, qdot_max]^n`` (no
    inverse: exactly 0 where ``J`` loses rank), and where ``J`` is not finite (a direct
    singularity, ``J`` infinite) the joint-rate slabs ``|K v| <= qdot_max``, which are. Otherwise
    (orientation freedoms, redundant actuation) the slabs' slice at zero angular velocity.
    """
    speeds = speed_limits_of(mech)
    if not len(v["joints"]):
        return np.zeros(0)
    rows = wrenches.force_rows(mech)
    if mech.has_orientation or mech.is_redundant:
        with np.errstate(invalid="ignore", over="ignore"):
            return velocity.rate_slab_radius(joint_rates(v, mech), joint_speed_limits=speeds, rows=rows)
    jac = v["jacobian"]
    out = velocity.isotropic_velocity(jac, joint_speed_limits=speeds)
    bad = ~np.all(np.isfinite(jac), axis=(-2, -1))
    if np.any(bad):
        with np.errstate(invalid="ignore", over="ignore"):
            out[bad] = velocity.rate_slab_radius(joint_rates(v, mech, bad), joint_speed_limits=speeds, rows=rows)
    return out


def peak_velocity(v: dict[str, Any], mech) -> FloatArray:
    """Fastest pure motion along each task axis (k, m), m/s or rad/s (``velocity.peak_velocities``)."""
    speeds = speed_limits_of(mech)
    if not len(v["joints"]):
        return np.zeros((0, mech.task_dim))
    with np.errstate(invalid="ignore", over="ignore"):
        return velocity.peak_velocities(joint_rates(v, mech), joint_speed_limits=speeds)

"""Carrying a running world's state into a recompiled model, element by element (adding and removing entities).

Elements are matched by name: bodies (every body the builder makes is named), actuators, tendons and welds; a
body's joints and geoms by their order in the body. Each surviving element gets exactly the values it had:

* **data**: ``qpos``, ``qvel``, ``qacc_warmstart`` (the solver's warm start), ``act``, ``ctrl``, ``eq_active``,
  ``xfrc_applied``, ``qfrc_applied``, ``time`` and the warning counters; nothing else in ``mjData`` survives a step
  (``mj_step`` recomputes it from these);
* **model**: every value the backend changes at run time (:data:`MODEL_FIELDS`: poses of moved static bodies,
  masses and inertias with what ``mj_setConst`` derives from them, gravity compensation, collision bits, weld
  poses, servo and motor torque limits).

**Bit for bit.** A MuJoCo step of the new model then gives the surviving bodies exactly the values the old model
would have given them, because (checked on MuJoCo 4.0, ``tests/backends/test_mujoco_runtime_entities.py``):

* the builder appends a new entity's elements after the existing ones, so their ids, their dof order and the
  order of their contacts (MuJoCo sorts the broad phase's pairs by body ids) are unchanged; removing keeps the
  relative order of what is left;
* constraint islands are on (MuJoCo's default, ``mjDSBL_ISLAND`` clear): Newton's solver runs per island, with a
  tolerance scaled by the island's own inertia, so a body that touches none of the old ones does not change their
  iterations;
* the Jacobian is sparse (``mjJAC_SPARSE``, set by :mod:`.builder`): sparse products sum the non-zeros of a row
  only, which adding or removing dofs elsewhere does not change; MuJoCo's dense ones (its ``auto`` choice below 60
  dofs) sum over all ``nv`` columns with unrolled partial sums whose grouping depends on ``nv``: a robot added to
  the clean-up world (50 -> 76 dofs) then moved the others by 1e-18 m from the first step;
* the scale of the no-slip solver's tolerance, ``1 / (stat.meaninertia * nv)``, is global even with islands: it
  is kept equal to the old model's (:func:`keep_noslip_scale`), so it stays that of the world as built;
* a new entity's dofs are warm-started from their unconstrained acceleration (:func:`warm_start`). MuJoCo
  chooses the warm start for the whole model at once: it compares the cost of last step's accelerations with that
  of the unconstrained ones, each summed over every dof and constraint, and starts every island from the cheaper.
  Starting the new dofs from the unconstrained accelerations adds the same terms to both sums; from zero, a 500 kg
  box added at rest made the others take the other start and moved them by 4e-7 m/s in the first step.

**What is not bit for bit.** After its first step, a new entity's own warm start enters that global comparison,
and it can flip the choice for the others when, without it, the two costs are within its share of each other.
Measured (``test_runtime_entities.py`` and the runs behind it): on the clean-up world, a box or a second robot
added while the robot drives leaves the others bit for bit for 1,000 steps and more; three balls thrown around far
from four objects kicked every 0.2 s flipped it after 80 to 1,200 steps (6 seeds of 6), the first difference
being 1e-18 to 4e-9 m, growing from there as any perturbation of colliding bodies does. Without the warm start
(``mjDSBL_WARMSTART``) all six ran 3,000 steps bit for bit, but the drive wheels' friction motors (:mod:`.servo`)
then miss their speed by 10 %: their 1e9 armature makes Newton's per-island tolerance loose, and it is the warm
start that carries the solution to convergence over the steps.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

Ints = npt.NDArray[np.int64]

_QPOS_SIZE = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
_DOF_SIZE = {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}

MODEL_FIELDS: dict[str, tuple[str, ...]] = {
    "body": ("body_pos", "body_quat", "body_mass", "body_inertia", "body_subtreemass", "body_invweight0",
             "body_gravcomp", "body_contype", "body_conaffinity"),
    "dof": ("dof_invweight0", "dof_M0"),
    "geom": ("geom_contype", "geom_conaffinity"),
    "actuator": ("actuator_forcerange", "actuator_acc0", "actuator_length0"),
    "tendon": ("tendon_frictionloss", "tendon_invweight0", "tendon_length0"),
    "eq": ("eq_data",),
}
"""Model arrays carried over, by kind of element: what the backend changes at run time (``body_pos``/``body_quat``
of a moved static object, masses, ``body_gravcomp``, collision bits, ``eq_data`` of a grasp, torque limits) and
what ``mj_setConst`` derives from masses (``*_invweight0``, ``dof_M0``, ``*_acc0``, ``*_length0``,
``body_subtreemass``)."""


@dataclass(frozen=True)
class ElementMap:
    """Where each surviving element of an old model is in a new one: parallel index arrays per kind.

    Attributes:
        old: Kind (``body``, ``jnt``, ``dof``, ``qpos``, ``geom``, ``actuator``, ``act``, ``tendon``, ``eq``) ->
            indices in the old model.
        new: The same kind -> the matching indices in the new model.
    """

    old: dict[str, Ints]
    new: dict[str, Ints]


def element_map(old: mujoco.MjModel, new: mujoco.MjModel) -> ElementMap:
    """Match the elements of ``old`` that still exist in ``new`` (the world body is left out: it never changes).

    Raises:
        ValueError: a body kept its name but not its joints or geoms (the builder never does this).
    """
    pairs: dict[str, list[tuple[int, int]]] = {k: [] for k in
                                               ("body", "jnt", "dof", "qpos", "geom", "actuator", "act",
                                                "tendon", "eq")}
    new_bodies = {str(new.body(b).name): b for b in range(1, new.nbody)}
    old_joints, new_joints = _by_body(old.jnt_bodyid, old.nbody), _by_body(new.jnt_bodyid, new.nbody)
    old_geoms, new_geoms = _by_body(old.geom_bodyid, old.nbody), _by_body(new.geom_bodyid, new.nbody)
    for b in range(1, old.nbody):
        nb = new_bodies.get(str(old.body(b).name))
        if nb is None:
            continue
        pairs["body"].append((b, nb))
        if len(old_joints[b]) != len(new_joints[nb]) or len(old_geoms[b]) != len(new_geoms[nb]):
            raise ValueError(f"body '{old.body(b).name}' changed its joints or geoms when recompiled")
        pairs["geom"] += zip(old_geoms[b], new_geoms[nb], strict=True)
        for j, nj in zip(old_joints[b], new_joints[nb], strict=True):
            pairs["jnt"].append((j, nj))
            jtype = int(old.jnt_type[j])
            pairs["qpos"] += _span(old.jnt_qposadr[j], new.jnt_qposadr[nj], _QPOS_SIZE.get(jtype, 1))
            pairs["dof"] += _span(old.jnt_dofadr[j], new.jnt_dofadr[nj], _DOF_SIZE.get(jtype, 1))
    for element, obj, count in (("actuator", mujoco.mjtObj.mjOBJ_ACTUATOR, "nu"),
                                ("tendon", mujoco.mjtObj.mjOBJ_TENDON, "ntendon"),
                                ("eq", mujoco.mjtObj.mjOBJ_EQUALITY, "neq")):
        for i in range(getattr(old, count)):
            name = mujoco.mj_id2name(old, obj, i)
            ni = mujoco.mj_name2id(new, obj, name) if name else -1
            if ni >= 0:
                pairs[element].append((i, ni))
    for a, na in pairs["actuator"]:
        pairs["act"] += _span(old.actuator_actadr[a], new.actuator_actadr[na], max(0, old.actuator_actnum[a]))
    arrays = {k: np.array(v, dtype=np.int64).reshape(-1, 2) for k, v in pairs.items()}
    return ElementMap({k: v[:, 0] for k, v in arrays.items()}, {k: v[:, 1] for k, v in arrays.items()})


def _by_body(owner: npt.NDArray[np.int32], nbody: int) -> list[list[int]]:
    groups: list[list[int]] = [[] for _ in range(nbody)]
    for i, b in enumerate(owner.tolist()):
        groups[b].append(i)
    return groups


def _span(old: int, new: int, size: int) -> list[tuple[int, int]]:
    return [(int(old) + k, int(new) + k) for k in range(size)]


def carry_model(src: mujoco.MjModel, dst: mujoco.MjModel, elements: ElementMap) -> None:
    """Copy the :data:`MODEL_FIELDS` of every surviving element from ``src`` to ``dst``; keep the no-slip scale."""
    for kind, fields in MODEL_FIELDS.items():
        old, new = elements.old[kind], elements.new[kind]
        for name in fields:
            getattr(dst, name)[new] = getattr(src, name)[old]
    dst.flg_gravcomp = bool(np.any(dst.body_gravcomp))
    keep_noslip_scale(dst, float(src.stat.meaninertia) * max(1, src.nv))


def carry_data(src: mujoco.MjData, dst: mujoco.MjData, elements: ElementMap) -> None:
    """Copy the state of every surviving element from ``src`` to ``dst`` (see the module docstring)."""
    old, new = elements.old, elements.new
    for name, kind in (("qpos", "qpos"), ("qvel", "dof"), ("qacc_warmstart", "dof"), ("qfrc_applied", "dof"),
                       ("xfrc_applied", "body"), ("ctrl", "actuator"), ("act", "act"), ("eq_active", "eq")):
        getattr(dst, name)[new[kind]] = getattr(src, name)[old[kind]]
    dst.time = src.time
    for i in range(int(mujoco.mjtWarning.mjNWARNING)):
        dst.warning[i].number = src.warning[i].number
        dst.warning[i].lastinfo = src.warning[i].lastinfo


def warm_start(model: mujoco.MjModel, data: mujoco.MjData, elements: ElementMap) -> None:
    """Give the dofs that did not exist before (not in ``elements``) their unconstrained acceleration
    (``qacc_smooth``) as warm start; ``mj_forward`` computes it and changes no state that ``mj_step`` reads."""
    new = np.ones(model.nv, dtype=bool)
    new[elements.new["dof"]] = False
    if new.any():
        mujoco.mj_forward(model, data)
        data.qacc_warmstart[new] = data.qacc_smooth[new]


def keep_noslip_scale(model: mujoco.MjModel, product: float) -> None:
    """Set ``model.stat.meaninertia`` so that ``meaninertia * max(1, nv)``, the no-slip solver's tolerance scale
    (MuJoCo's ``solNoSlip``), equals ``product`` exactly, or to the nearest double if none does."""
    n = float(max(1, model.nv))
    x = product / n
    best = x
    for _ in range(16):
        y = x * n
        if y == product:
            best = x
            break
        if abs(y - product) < abs(best * n - product):
            best = x
        x = float(np.nextafter(x, np.inf if y < product else -np.inf))
    model.stat.meaninertia = best


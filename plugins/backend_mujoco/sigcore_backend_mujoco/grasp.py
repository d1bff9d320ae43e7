"""Grasps as weld equality constraints, created disabled at build and switched on with ``mjData.eq_active``.

MuJoCo cannot add a constraint to a compiled model cheaply, so the builder adds one disabled weld per (gripper
part, graspable dynamic object). A grasp writes the weld's ``eq_data`` row so that the constraint holds the
*current* relative pose, then activates it. Layout of a body-based weld's ``eq_data`` (``mjNEQDATA`` = 12 in
MuJoCo 4.0):

==========  ====================================================================================
``[0:3]``   anchor, in the frame of body2 (the object): 0, its frame origin
``[3:6]``   relpose position: the anchor in the frame of body1 (the hand)
``[6:10]``  relpose quaternion: orientation of body2 relative to body1, ``conj(q_hand) * q_object``
``[10]``    torquescale: 1
``[11]``    non-zero if ``mj_setConst`` should recompute ``[3:10]`` at ``qpos0``: kept 0
==========  ====================================================================================

While attached, the object does not collide with the robot holding it (see :mod:`.collision`).
"""

from __future__ import annotations

import mujoco

from sigcore.errors import BackendRefusal
from sigcore.geometry import quat_conj, quat_mul

from .layout import EntityIndex, Layout


def weld_id(layout: Layout, robot: EntityIndex, part: str, obj: EntityIndex) -> int:
    """The weld between ``robot``'s ``part`` and ``obj``.

    Raises:
        BackendRefusal: there is none (not a gripper, or the object is not graspable or static); the
            message lists the pairs that exist.
    """
    weld = layout.welds.get((robot.name, part, obj.name))
    if weld is None:
        pairs = sorted(f"{p} + {o}" for (r, p, o) in layout.welds if r == robot.name)
        raise BackendRefusal(f"'{robot.name}' cannot attach '{obj.name}' to '{part}': only <gripper> parts "
                           f"hold graspable, non-static objects; possible: {', '.join(pairs) or 'none'}")
    return weld


def activate(model: mujoco.MjModel, data: mujoco.MjData, weld: int, hand: int, obj: int) -> None:
    """Set ``weld`` to the current pose of body ``obj`` relative to body ``hand`` and switch it on.

    ``data`` must hold current kinematics (``xpos``, ``xquat``, ``xmat``).
    """
    rot = data.xmat[hand].reshape(3, 3)
    row = model.eq_data[weld]
    row[0:3] = 0.0
    row[3:6] = rot.T @ (data.xpos[obj] - data.xpos[hand])
    row[6:10] = quat_mul(quat_conj(data.xquat[hand]), data.xquat[obj])
    row[10] = 1.0
    row[11] = 0.0
    data.eq_active[weld] = 1

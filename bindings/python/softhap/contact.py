"""softhap.Tool (an sh_tool_id: a rigid tool posed by the host) and softhap.Obstacle (an
sh_obstacle_id: a static rigid obstacle) of a World, and their ContactState.

Both are made by World.add_tool and World.add_obstacle. Like a Body, they are ids in their
world: they keep the World alive, and raise softhap.Error (SH_ERR_INVALID_HANDLE) once
destroyed or once the world is closed.
"""

import ctypes

import numpy as np

from . import _arrays
from ._lib import sh_contact_state
from ._entity import WorldEntity
from ._loaded import check, lib
from ._record import Record, record_of


class ContactState(Record):
    """Contact state of a tool or obstacle after the last step (sh_contact_state): force (N)
    and torque (N m, about its position) of the reaction on the tool/obstacle as (3,) arrays
    (world frame), contact_count (contact points in the last step), max_depth (deepest
    penetration, m) and penetration_volume (m^3: the sum over touching surface nodes of depth
    times the node's share of surface area)."""


def _contact_state(raw):
    return record_of(
        ContactState,
        raw,
        force=np.array(raw.force[:], dtype=np.float64),
        torque=np.array(raw.torque[:], dtype=np.float64),
    )


class _Collider(WorldEntity):
    """What Tool and Obstacle share: an id in a World, the contact state read after a step and
    destroy().

    A subclass sets _kind, _is_valid, _get_contact (the C function reading its state) and
    _destroy (the C function removing it)."""

    _get_contact = None
    _destroy = None

    @property
    def valid(self):
        """Same as is_valid."""
        return self.is_valid

    def destroy(self):
        """Remove it from its world; its id becomes stale."""
        handle = self._world_handle(self._destroy)
        check(getattr(lib, self._destroy)(handle, self._id), self._destroy)

    @property
    def contact_state(self):
        """The ContactState after the last step (or World.solve_static): force, torque (arrays,
        the reaction on the tool or obstacle, world frame), contact_count, max_depth (m) and
        penetration_volume (m^3)."""
        handle = self._world_handle(self._get_contact)
        raw = sh_contact_state()
        function = getattr(lib, self._get_contact)
        check(function(handle, self._id, ctypes.byref(raw)), self._get_contact)
        return _contact_state(raw)

    @property
    def force(self):
        """Reaction force (N) on it after the last step, a (3,) array (world frame)."""
        return self.contact_state["force"]

    @property
    def torque(self):
        """Reaction torque (N m) on it about its position after the last step, a (3,) array."""
        return self.contact_state["torque"]

    @property
    def contacts(self):
        """Number of contact points in the last step."""
        return self.contact_state["contact_count"]

    @property
    def max_depth(self):
        """Deepest penetration (m) in the last step."""
        return self.contact_state["max_depth"]

    @property
    def penetration_volume(self):
        """Volume (m^3) of body material inside it after the last step (approximate)."""
        return self.contact_state["penetration_volume"]


class Tool(_Collider):
    """A rigid tool of a World (an sh_tool_id), posed by the host between steps.

    Made by World.add_tool. tool.set_pose() gives the pose the next World.step moves it to
    (its velocity is the pose difference over dt unless set_velocity gives it); after the step
    force, torque, contacts, max_depth, penetration_volume and contact_state tell the reaction
    on the tool. After destroy() (or once the World is closed) every call raises softhap.Error
    (SH_ERR_INVALID_HANDLE).
    """

    _kind = "tool"
    _is_valid = "sh_tool_is_valid"
    _get_contact = "sh_tool_get_contact"
    _destroy = "sh_tool_destroy"

    @property
    def pose(self):
        """(position, orientation): the pose the next step takes the tool to, as numpy arrays
        of 3 (m) and 4 (unit quaternion w, x, y, z) (sh_tool_get_pose)."""
        handle = self._world_handle("sh_tool_get_pose")
        position = np.zeros(3)
        orientation = np.zeros(4)
        check(
            lib.sh_tool_get_pose(
                handle, self._id, _arrays.double_ptr(position), _arrays.double_ptr(orientation)
            ),
            "sh_tool_get_pose",
        )
        return position, orientation

    def set_pose(self, position, orientation=(1.0, 0.0, 0.0, 0.0)):
        """Pose the tool for the next step: position (3 floats, m, world) and orientation (a
        unit quaternion (w, x, y, z); it is normalised). The step moves the tool from its last
        pose to this one. A non-finite position or a zero or non-finite quaternion raises
        softhap.Error (SH_ERR_INVALID_ARGUMENT) and the tool keeps its pose."""
        handle = self._world_handle("sh_tool_set_pose")
        position = _arrays.float_array(position, "position", (3,))
        orientation = _arrays.float_array(orientation, "orientation", (4,))
        check(
            lib.sh_tool_set_pose(
                handle, self._id, _arrays.double_ptr(position), _arrays.double_ptr(orientation)
            ),
            "sh_tool_set_pose",
        )

    def set_velocity(self, linear, angular=(0.0, 0.0, 0.0)):
        """Give the tool's velocity for the next step instead of deriving it from successive
        poses: linear (m/s) of its position and angular (rad/s), world frame. Only the
        contact's damping and friction see it."""
        handle = self._world_handle("sh_tool_set_velocity")
        linear = _arrays.float_array(linear, "linear", (3,))
        angular = _arrays.float_array(angular, "angular", (3,))
        check(
            lib.sh_tool_set_velocity(
                handle, self._id, _arrays.double_ptr(linear), _arrays.double_ptr(angular)
            ),
            "sh_tool_set_velocity",
        )

    def wrench(self):
        """(force, torque): the reaction on the tool after the last step, two (3,) arrays
        (N and N m about the tool's position, world frame; sh_tool_get_wrench)."""
        handle = self._world_handle("sh_tool_get_wrench")
        force = np.zeros(3)
        torque = np.zeros(3)
        check(
            lib.sh_tool_get_wrench(
                handle, self._id, _arrays.double_ptr(force), _arrays.double_ptr(torque)
            ),
            "sh_tool_get_wrench",
        )
        return force, torque


class Obstacle(_Collider):
    """A static rigid obstacle of a World (an sh_obstacle_id): a plane, sphere, capsule, box or
    convex hull that never moves.

    Made by World.add_obstacle. After a step force, torque, contacts, max_depth,
    penetration_volume and contact_state tell the reaction on the obstacle. After destroy() (or
    once the World is closed) every call raises softhap.Error (SH_ERR_INVALID_HANDLE).
    """

    _kind = "obstacle"
    _is_valid = "sh_obstacle_is_valid"
    _get_contact = "sh_obstacle_get_contact"
    _destroy = "sh_obstacle_destroy"

"""softhap.Tool (an sh_tool_id: a rigid tool posed by the host) and softhap.Obstacle (an
sh_obstacle_id: a static rigid obstacle) of a World, their ContactState, and the World methods
that add them and set contact between bodies (World.add_tool, add_obstacle, set_body_contact
and clear_body_contact, defined here in WorldContacts, which World inherits).

Like a Body, a Tool or Obstacle is an id in its world: it keeps the World alive, and raises
softhap.Error (SH_ERR_INVALID_HANDLE) once destroyed or once the world is closed.

The keyword defaults are the C library's, as in softhap.world (checked by
tests/python/test_defaults.py); those marked with default() are read by some kinds only, or
clash with friction=, and are rejected when given where they do not apply.
"""

from __future__ import annotations

import ctypes
from typing import TYPE_CHECKING, Any, Mapping, Optional, Tuple, cast

import numpy as np
from numpy.typing import ArrayLike

from . import _arrays, _defs, _lib
from ._defs import default
from ._entity import WorldEntity
from ._handle import OwnedHandle
from ._lib import sh_contact_state, sh_cut_def, sh_obstacle_id, sh_tool_id
from ._loaded import check, lib
from ._record import Record, record_of
from .body import Body, body_id_in

if TYPE_CHECKING:
    from .world import World


class ContactState(Record):
    """Contact state of a tool or obstacle after the last step (sh_contact_state): force (N)
    and torque (N m, about its position) of the reaction on the tool/obstacle as (3,) arrays
    (world frame), contact_count (contact points in the last step), max_depth (deepest
    penetration, m) and penetration_volume (m^3: the sum over touching surface nodes of depth
    times the node's share of surface area)."""


def _contact_state(raw: sh_contact_state) -> ContactState:
    return record_of(
        ContactState,
        raw,
        force=np.array(raw.force[:], dtype=np.float64),
        torque=np.array(raw.torque[:], dtype=np.float64),
    )


class _Collider(WorldEntity):
    """What Tool and Obstacle share: an id in a World, the contact state read after a step and
    destroy().

    A subclass sets _kind, _is_valid, _id_type, _create and _destroy (the C functions making
    and removing it) and _get_contact (the C function reading its state)."""

    _create: str = ""
    _get_contact: str = ""
    _destroy: str = ""

    @property
    def valid(self) -> bool:
        """Same as is_valid."""
        return self.is_valid

    def destroy(self) -> None:
        """Remove it from its world; its id becomes stale."""
        handle = self._world_handle(self._destroy)
        check(getattr(lib, self._destroy)(handle, self._cid), self._destroy)

    @property
    def contact_state(self) -> ContactState:
        """The ContactState after the last step (or World.solve_static): force, torque (arrays,
        the reaction on the tool or obstacle, world frame), contact_count, max_depth (m) and
        penetration_volume (m^3)."""
        handle = self._world_handle(self._get_contact)
        raw = sh_contact_state()
        function = getattr(lib, self._get_contact)
        check(function(handle, self._cid, ctypes.byref(raw)), self._get_contact)
        return _contact_state(raw)

    @property
    def force(self) -> np.ndarray:
        """Reaction force (N) on it after the last step, a (3,) array (world frame)."""
        return self.contact_state["force"]

    @property
    def torque(self) -> np.ndarray:
        """Reaction torque (N m) on it about its position after the last step, a (3,) array."""
        return self.contact_state["torque"]

    @property
    def contacts(self) -> int:
        """Number of contact points in the last step."""
        return self.contact_state["contact_count"]

    @property
    def max_depth(self) -> float:
        """Deepest penetration (m) in the last step."""
        return self.contact_state["max_depth"]

    @property
    def penetration_volume(self) -> float:
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
    _id_type = sh_tool_id
    _create = "sh_tool_create"
    _get_contact = "sh_tool_get_contact"
    _destroy = "sh_tool_destroy"

    @property
    def pose(self) -> Tuple[np.ndarray, np.ndarray]:
        """(position, orientation): the pose the next step takes the tool to, as numpy arrays
        of 3 (m) and 4 (unit quaternion w, x, y, z) (sh_tool_get_pose)."""
        handle = self._world_handle("sh_tool_get_pose")
        position = np.zeros(3)
        orientation = np.zeros(4)
        check(
            lib.sh_tool_get_pose(
                handle, self._cid, _arrays.double_ptr(position), _arrays.double_ptr(orientation)
            ),
            "sh_tool_get_pose",
        )
        return position, orientation

    def set_pose(self, position: ArrayLike, orientation: ArrayLike = (1.0, 0.0, 0.0, 0.0)) -> None:
        """Pose the tool for the next step: position (3 floats, m, world) and orientation (a
        unit quaternion (w, x, y, z); it is normalised). The step moves the tool from its last
        pose to this one. A non-finite position or a zero or non-finite quaternion raises
        softhap.Error (SH_ERR_INVALID_ARGUMENT) and the tool keeps its pose."""
        handle = self._world_handle("sh_tool_set_pose")
        position = _arrays.float_array(position, "position", (3,))
        orientation = _arrays.float_array(orientation, "orientation", (4,))
        check(
            lib.sh_tool_set_pose(
                handle, self._cid, _arrays.double_ptr(position), _arrays.double_ptr(orientation)
            ),
            "sh_tool_set_pose",
        )

    def set_velocity(self, linear: ArrayLike, angular: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        """Give the tool's velocity for the next step instead of deriving it from successive
        poses: linear (m/s) of its position and angular (rad/s), world frame. Only the
        contact's damping and friction see it."""
        handle = self._world_handle("sh_tool_set_velocity")
        linear = _arrays.float_array(linear, "linear", (3,))
        angular = _arrays.float_array(angular, "angular", (3,))
        check(
            lib.sh_tool_set_velocity(
                handle, self._cid, _arrays.double_ptr(linear), _arrays.double_ptr(angular)
            ),
            "sh_tool_set_velocity",
        )

    def set_cutting(
        self,
        edge: Optional[ArrayLike] = ((0.0, 0.0, -0.005), (0.0, 0.0, 0.005)),
        criterion: str = "geometric",
        sharpness: float = 1.0,
        resolution: float = 0.0,
    ) -> None:
        """Make the tool a cutting tool, or an ordinary one again with ``set_cutting(None)``.

        edge is the blade's cutting edge, two points in the tool's local frame (m). At every
        World.step the surface the edge sweeps from the tool's last pose to its new pose cuts
        every body it passes through (see Body.cut); the report's cut_faces and
        topology_seconds count it. criterion: "geometric" (the material the edge sweeps
        separates) or "physical" (the edge holds the material just ahead of it and drags it
        along, and it breaks one resolution ahead once the work the blade did since the last
        break pays toughness / sharpness x engaged length x resolution: in steady cutting the
        blade's force is toughness x engaged length / sharpness; tool.force includes it).
        sharpness: the blade's kappa (> 0; 1 a scalpel, larger is sharper). resolution: the
        edge length (m) the material is refined to around the blade's edge and the path of
        its ends before it cuts, so that the opening reaches to within about this of the blade
        on a coarse mesh (and, physically, how far the crack advances per break); 0 means a
        quarter of the blade's length."""
        handle = self._world_handle("sh_tool_set_cutting")
        if edge is None:
            check(lib.sh_tool_set_cutting(handle, self._cid, None), "sh_tool_set_cutting")
            return
        criteria = _lib.CUT_CRITERIA
        if criterion not in criteria:
            raise ValueError("criterion must be one of %s, got %r" % (sorted(criteria), criterion))
        points = _arrays.float_array(edge, "edge", (2, 3))
        raw = sh_cut_def()
        lib.sh_cut_def_default(ctypes.byref(raw))
        raw.criterion = criteria[criterion]
        for e in range(2):
            for k in range(3):
                raw.edge[e][k] = float(points[e, k])
        raw.sharpness = float(sharpness)
        raw.resolution = float(resolution)
        check(lib.sh_tool_set_cutting(handle, self._cid, ctypes.byref(raw)), "sh_tool_set_cutting")

    def wrench(self) -> Tuple[np.ndarray, np.ndarray]:
        """(force, torque): the reaction on the tool after the last step, two (3,) arrays
        (N and N m about the tool's position, world frame; sh_tool_get_wrench)."""
        handle = self._world_handle("sh_tool_get_wrench")
        force = np.zeros(3)
        torque = np.zeros(3)
        check(
            lib.sh_tool_get_wrench(
                handle, self._cid, _arrays.double_ptr(force), _arrays.double_ptr(torque)
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
    _id_type = sh_obstacle_id
    _create = "sh_obstacle_create"
    _get_contact = "sh_obstacle_get_contact"
    _destroy = "sh_obstacle_destroy"


class WorldContacts(OwnedHandle):
    """The World methods that add tools and obstacles and set contact between bodies: World
    inherits them from this base class, which lives here beside the Tool and Obstacle they
    make. Not used on its own."""

    def add_tool(
        self,
        kind: str,
        radius: float = default(5e-3),
        half_length: float = default(0.0),
        half_extents: Optional[ArrayLike] = None,
        points: Optional[ArrayLike] = None,
        position: ArrayLike = (0.0, 0.0, 0.0),
        orientation: ArrayLike = (1.0, 0.0, 0.0, 0.0),
        stiffness: float = 1e4,
        exponent: float = 1.5,
        damping: float = 0.2,
        static_friction: float = default(0.0),
        dynamic_friction: float = default(0.0),
        slip_velocity: float = 1e-3,
        capacity: int = 4096,
        friction: Optional[float] = None,
    ) -> Tool:
        """Add a rigid tool posed by the host (sh_tool_create) and return its Tool.

        kind and its shape parameters (only the kind's are accepted; the defaults are those
        of sh_collider_def_default):
            "sphere": radius (m), centred on the pose;
            "capsule": radius and half_length (m) of the segment along local z (at most 1024
            radii); spheres and capsules are held by a face between its nodes, boxes and
            convex hulls push the nodes inside them only;
            "box": half_extents, 3 half widths along the local axes (m; no default);
            "convex": points, an (n, 3) array (m, local frame, n >= 4, not all in one plane;
            no default; needs a library built with libccd, else SH_ERR_UNSUPPORTED);
            "plane" is an obstacle only: the C library rejects it as a tool.
        position (m, world) and orientation (unit quaternion (w, x, y, z)): the initial pose.
        The contact law against every body (sh_contact_params, defaults of
        sh_contact_params_default): stiffness lambda (N/m^n), exponent n and damping alpha
            (s/m) of the Hunt-Crossley force F = lambda x^n (1 + 3/2 alpha x');
            static_friction mu_s and dynamic_friction mu_d (mu_s >= mu_d is required, so set
            both, or use friction=mu for mu_s = mu_d = mu; None: not used); slip_velocity
            (m/s) below which friction is viscous; capacity (most contact points kept per
            step).
        Unknown names raise ValueError; invalid values raise softhap.Error
        (SH_ERR_INVALID_ARGUMENT, the message naming the field).
        """
        arguments = dict(locals())
        world = cast("World", self)
        return Tool(world, self._create_collider(Tool, kind, arguments, position, orientation))

    def add_obstacle(
        self,
        kind: str,
        radius: float = default(5e-3),
        half_length: float = default(0.0),
        half_extents: Optional[ArrayLike] = None,
        points: Optional[ArrayLike] = None,
        normal: ArrayLike = default((0.0, 0.0, 1.0)),
        position: ArrayLike = (0.0, 0.0, 0.0),
        orientation: ArrayLike = default((1.0, 0.0, 0.0, 0.0)),
        stiffness: float = 1e4,
        exponent: float = 1.5,
        damping: float = 0.2,
        static_friction: float = default(0.0),
        dynamic_friction: float = default(0.0),
        slip_velocity: float = 1e-3,
        capacity: int = 4096,
        friction: Optional[float] = None,
    ) -> Obstacle:
        """Add a static rigid obstacle (sh_obstacle_create) and return its Obstacle.

        kind and its shape parameters (only the kind's are accepted; the defaults are those
        of sh_collider_def_default):
            "plane": the outward normal (world frame); the plane passes through position and
            the obstacle is the half-space behind it (a plane takes no orientation);
            "sphere", "capsule", "box" and "convex": as World.add_tool.
        position (m, world) and orientation (unit quaternion (w, x, y, z)): its pose.
        The contact law (stiffness, exponent, damping, static_friction, dynamic_friction,
        friction, slip_velocity, capacity): as World.add_tool.
        Unknown names raise ValueError; invalid values raise softhap.Error.
        """
        arguments = dict(locals())
        if kind == "plane" and _defs.given(orientation):
            raise ValueError(
                "orientation= is not a parameter of a 'plane' obstacle (it takes: position=, "
                "normal=)"
            )
        world = cast("World", self)
        return Obstacle(world, self._create_collider(Obstacle, kind, arguments, position, orientation))

    def _create_collider(
        self,
        entity: type[_Collider],
        kind: str,
        arguments: Mapping[str, Any],
        position: Optional[ArrayLike],
        orientation: Optional[ArrayLike],
    ) -> int:
        """The id that entity's create function (sh_tool_create or sh_obstacle_create) gives
        the collider of shape kind, its keyword arguments and its pose."""
        function = entity._create
        handle = self._require_handle(function)
        definition, arrays = _defs.collider_def(kind, arguments, position, orientation)
        collider = entity._id_type()
        check(
            getattr(lib, function)(handle, ctypes.byref(definition), ctypes.byref(collider)),
            function,
        )
        del arrays  # the C library has copied the points
        return collider.value

    def set_body_contact(
        self,
        body_a: Body,
        body_b: Body,
        stiffness: float = 1e4,
        exponent: float = 1.5,
        damping: float = 0.2,
        static_friction: float = default(0.0),
        dynamic_friction: float = default(0.0),
        slip_velocity: float = 1e-3,
        capacity: int = 4096,
        friction: Optional[float] = None,
    ) -> None:
        """Enable contact between two different FEM bodies of this world with the given
        contact law (sh_world_set_body_contact; keywords and defaults as World.add_tool);
        calling it again replaces the law. Each step the surface nodes of each body inside
        the other are pushed out through the other's nearest surface triangle. A mass-spring
        body raises softhap.Error (SH_ERR_UNSUPPORTED).
        """
        arguments = dict(locals())
        handle = self._require_handle("sh_world_set_body_contact")
        a = body_id_in(self, body_a, "body_a")
        b = body_id_in(self, body_b, "body_b")
        params = _defs.contact_params(arguments)
        check(
            lib.sh_world_set_body_contact(handle, a, b, ctypes.byref(params)),
            "sh_world_set_body_contact",
        )

    def clear_body_contact(self, body_a: Body, body_b: Body) -> None:
        """Disable contact between two bodies (sh_world_set_body_contact with NULL params); a
        pair without contact is left as it is."""
        handle = self._require_handle("sh_world_set_body_contact")
        a = body_id_in(self, body_a, "body_a")
        b = body_id_in(self, body_b, "body_b")
        check(lib.sh_world_set_body_contact(handle, a, b, None), "sh_world_set_body_contact")

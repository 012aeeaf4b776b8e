"""The identity shared by Body, Tool and Obstacle: a generation-checked id in a World."""

from __future__ import annotations

from ctypes import Structure
from typing import TYPE_CHECKING, cast

from ._loaded import closed_error, lib

if TYPE_CHECKING:
    from .world import World


class WorldEntity:
    """Base of the Python objects that name one entity of a World by its id.

    A subclass sets _kind (the word used in the closed-world error, "body"), _is_valid (the
    name of the C function telling whether the id is live, "sh_body_is_valid") and _id_type
    (its C id struct, sh_body_id). The World owns the entity's data; the object keeps its World
    alive.
    """

    _kind: str = ""
    _is_valid: str = ""
    _id_type: type[Structure] = Structure

    def __init__(self, world: World, entity_id: int) -> None:
        """Wrap the id entity_id of world (use the World's add_* methods rather than this)."""
        self._world = world
        self._cid = self._id_type(int(entity_id))  # the id as the C functions take it

    def __repr__(self) -> str:
        return "<softhap.%s id=%#x>" % (type(self).__name__, self.id)

    @property
    def world(self) -> World:
        """The World this entity belongs to."""
        return self._world

    @property
    def id(self) -> int:
        """The generation-checked id (an int; 0 is the null id)."""
        return cast(int, self._cid.value)

    @property
    def is_valid(self) -> bool:
        """True while the id names a live entity of an open world."""
        if self._world.closed:
            return False
        return bool(getattr(lib, self._is_valid)(self._world._handle, self._cid))

    def _world_handle(self, function: str) -> int:
        if self._world.closed:
            raise closed_error("world of this %s" % self._kind, function)
        return cast(int, self._world._handle)  # not None: the world is open

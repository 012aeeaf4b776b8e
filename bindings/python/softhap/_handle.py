"""The lifetime shared by Mesh and World: a C object owned through an opaque handle."""

from __future__ import annotations

from typing import Literal, Optional, TypeVar

from ._loaded import check, closed_error, lib

_Owner = TypeVar("_Owner", bound="OwnedHandle")


class OwnedHandle:
    """Base of the Python objects that own one C object (self._handle, None once closed).

    A subclass sets _kind (the word used in the closed-object error, "mesh") and _destroy (the
    name of the C function that frees the object, "sh_mesh_destroy").
    """

    _kind: str = ""
    _destroy: str = ""
    _handle: Optional[int]

    def close(self) -> None:
        """Destroy the C object now. Safe to call more than once; later use raises softhap.Error."""
        handle, self._handle = self._handle, None
        if handle is not None:
            check(getattr(lib, self._destroy)(handle), self._destroy)

    @property
    def closed(self) -> bool:
        """True once close() has been called."""
        return self._handle is None

    def __enter__(self: _Owner) -> _Owner:
        """Use the object in a ``with`` block; it is closed at the end."""
        return self

    def __exit__(self, *exc_info: object) -> Literal[False]:
        """Close the object at the end of a ``with`` block."""
        self.close()
        return False

    def __del__(self) -> None:
        """Free the C object if close() was not called."""
        handle = getattr(self, "_handle", None)
        if handle is not None:
            self._handle = None
            try:
                getattr(lib, self._destroy)(handle)
            except Exception:  # interpreter shutdown: ctypes may already be torn down
                pass

    def _require_handle(self, function: Optional[str] = None) -> int:
        if self._handle is None:
            raise closed_error(self._kind, function)
        return self._handle

"""softhap.Error: the exception every failing C call raises."""

from __future__ import annotations

from typing import Any, Optional, Tuple

from ._lib import Status


def status_name(status: int) -> str:
    """Return the C enum name of a status code ("SH_ERR_PARSE"), or "SH_STATUS_<n>" if unknown."""
    try:
        return Status(status).name
    except ValueError:
        return "SH_STATUS_%d" % int(status)


class Error(Exception):
    """A softhap C call failed.

    Attributes:
        status: the sh_status code (a softhap.Status, which is an int).
        status_name: its C name, e.g. "SH_ERR_PARSE".
        message: sh_last_error_message() of the failed call (which file and line, element,
            node or parameter), or a description written by the bindings.
        function: the C function that failed (e.g. "sh_mesh_load"), or None.
        report: for a failed sh_world_step that stepped the bodies, the StepReport of that
            step (the other bodies still advanced); for sh_world_solve_static, the StaticReport
            of what was tried when the library filled it; None otherwise.
    """

    def __init__(
        self, status: int, message: str, function: Optional[str] = None, report: Any = None
    ) -> None:
        """Make an error for status (an sh_status value) with the given detail message."""
        try:
            status = Status(status)
        except ValueError:
            status = int(status)
        self.status = status
        self.status_name = status_name(status)
        self.message = message
        self.function = function
        self.report = report
        super().__init__(self._describe())

    def __reduce__(self) -> Tuple[type, Tuple[int, str, Optional[str], Any]]:
        """Pickle support (for multiprocessing): rebuild from the same fields."""
        return (type(self), (int(self.status), self.message, self.function, self.report))

    def _describe(self) -> str:
        where = "%s: " % self.function if self.function else ""
        if self.message:
            return "%s%s: %s" % (where, self.status_name, self.message)
        return "%s%s" % (where, self.status_name)

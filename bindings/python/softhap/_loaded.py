"""The loaded C library (found, version-checked and declared at import) and status checking."""

from __future__ import annotations

from typing import Any, Callable, Optional

from ._errors import Error
from ._lib import Status, load_library

lib = load_library()


def last_error_message() -> str:
    """Return sh_last_error_message() of the calling thread as text."""
    raw = lib.sh_last_error_message()
    return raw.decode("utf-8", errors="replace") if raw else ""


def status_string(status: int) -> str:
    """Return sh_status_string(status) as text ("SH_ERR_PARSE: malformed file content")."""
    raw = lib.sh_status_string(int(status))
    return raw.decode("utf-8", errors="replace") if raw else ""


def check(status: int, function: str, report: Optional[Callable[[], Any]] = None) -> None:
    """Raise softhap.Error if status (returned by the C function named function) is not SH_OK.
    report: None, or a callable giving what the error carries as .report (called only on
    failure)."""
    if status != Status.SH_OK:
        message = last_error_message() or status_string(status)
        raise Error(status, message, function, report=report() if report else None)


def closed_error(what: str, function: Optional[str] = None) -> Error:
    """Return the Error raised when a closed World or Mesh (or a Body of a closed World) is used."""
    return Error(
        Status.SH_ERR_INVALID_HANDLE,
        "the %s has been closed; its C object no longer exists" % what,
        function,
    )

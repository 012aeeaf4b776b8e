"""The loaded C library (found, version-checked and declared at import) and status checking."""

from __future__ import annotations

import ctypes
import logging
from typing import Any, Callable, Optional

from ._errors import Error
from ._lib import LOG_LEVELS, Status, load_library

lib = load_library()

#: The library's messages (sh_set_log_callback) go to this logger: sh_log_level DEBUG, INFO and
#: WARNING become logging's levels of the same names.
logger = logging.getLogger("softhap")
_LEVELS = {LOG_LEVELS["debug"]: logging.DEBUG, LOG_LEVELS["info"]: logging.INFO, LOG_LEVELS["warning"]: logging.WARNING}
_LOG_FN = ctypes.CFUNCTYPE(None, ctypes.c_int, ctypes.c_char_p, ctypes.c_void_p)


def _forward(level: int, message: bytes, _user: Any) -> None:
    logger.log(_LEVELS.get(level, logging.WARNING), message.decode("utf-8", errors="replace"))


_forward_c = _LOG_FN(_forward)  # kept alive as long as the module: the library holds its address
lib.sh_set_log_callback(ctypes.cast(_forward_c, ctypes.c_void_p), None)  # at import no object lives


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

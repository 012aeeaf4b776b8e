"""softhap: Python bindings (ctypes + numpy) of the softhap C library for real-time soft-tissue
simulation. They mirror the C API of include/softhap/softhap.h:

    import softhap
    liver = softhap.Mesh.load("liver.msh")
    with softhap.World(gravity=(0, 0, -9.81)) as world:
        body = world.add_fem_body(liver, model="corotational", young=5e3, poisson=0.45)
        body.fix_nodes([0, 1, 2])
        tool = world.add_tool("sphere", radius=0.005, position=(0, 0, 0.1))
        report = world.step(1e-3)
        print(report.substeps, report.contact_count, tool.force, body.positions[:3])

The C library is found through $SOFTHAP_LIBRARY, else libsofthap.so next to this package, else
<repo>/build/libsofthap.so; importing refuses a library of another version. Every failing C
call raises softhap.Error with the status and sh_last_error_message().
"""

from __future__ import annotations

from typing import FrozenSet

from ._errors import Error, status_name
from ._lib import SH_VERSION, FeatureKind, HapticFault, Status, WarningKind, version_string
from ._loaded import lib as _c_library
from ._loaded import status_string
from ._record import BodyInfo, CutReport, MeshInfo, StaticReport, StepReport
from .contact import ContactState, Obstacle, Tool
from .device import DeviceMapping
from .haptic import Haptic, HapticResult
from .mesh import Mesh
from .mesh_exchange import UnitsWarning
from .body import Body
from .world import World
from .series import Series
from .demo import demo
from .tetrahedralize import tetrahedralize

__version__ = version_string(SH_VERSION)

#: Path of the loaded C library.
library_path = _c_library.softhap_path


def version() -> int:
    """Version of the loaded C library in the SH_VERSION encoding (MAJOR*1000000 + MINOR*1000
    + PATCH); equal to softhap.SH_VERSION, since import refuses a mismatch."""
    return int(_c_library.sh_version())


def build_features() -> FrozenSet[str]:
    """The optional components compiled into the loaded library, as a frozenset of names
    ("SH_FEATURE_CHOLMOD", "SH_FEATURE_CCD") from the sh_build_features() bit mask."""
    bits = int(_c_library.sh_build_features())
    return frozenset(kind.name for kind in FeatureKind if bits & int(kind))


__all__ = [
    "Body",
    "BodyInfo",
    "ContactState",
    "Series",
    "CutReport",
    "DeviceMapping",
    "Error",
    "FeatureKind",
    "Haptic",
    "HapticFault",
    "HapticResult",
    "Mesh",
    "MeshInfo",
    "Obstacle",
    "SH_VERSION",
    "StaticReport",
    "Status",
    "StepReport",
    "Tool",
    "UnitsWarning",
    "WarningKind",
    "World",
    "build_features",
    "demo",
    "library_path",
    "status_name",
    "status_string",
    "tetrahedralize",
    "version",
    "version_string",
]

"""softhap.World (sh_world): creates, steps and solves a scene, and adds and removes its bodies
and haptic contexts. Its methods adding tools and obstacles and setting contact between bodies
are in softhap.contact (WorldContacts, World's base class), beside the Tool and Obstacle.

The keyword defaults in the signatures are the C library's *_def_default values (see
src/capi/*.cpp). They are written out as literals rather than read from the library at import:
that way they read as numbers in the source, in IDEs and in tools that parse the source
without loading the library, as well as in help(); tests/python/test_defaults.py calls the
*_def_default functions through ctypes and fails if any of them drifts. Those marked with
default() are read by some kinds only (see softhap._defs).
"""

from __future__ import annotations

import ctypes
from typing import Dict, Optional, Tuple, Union

from numpy.typing import ArrayLike

from . import _arrays, _defs
from ._defs import default
from ._handle import OwnedHandle
from ._lib import SH_WARN_COUNT, WarningKind, sh_body_id, sh_static_report, sh_step_report
from ._loaded import check, lib
from ._record import StaticReport, StepReport, static_report, step_report
from .body import Body, body_id_in
from .contact import Tool, WorldContacts
from .haptic import Haptic
from .mesh import Mesh


class World(WorldContacts):
    """A simulation world (sh_world): owns bodies and steps them.

    World(gravity=(0, 0, -9.81)) creates one. The C world and all its bodies are freed by
    close(), at the end of a ``with`` block, or when the World is garbage collected (a Body
    keeps its World alive). add_tool, add_obstacle, set_body_contact and clear_body_contact
    come from its base class softhap.contact.WorldContacts.
    """

    _kind = "world"
    _destroy = "sh_world_destroy"

    def __init__(self, gravity: ArrayLike = (0.0, 0.0, -9.81), error_estimate: bool = False) -> None:
        """Create a world with the given gravitational acceleration (3 floats, m/s^2).

        error_estimate=True makes every step also take each body over dt in two half steps
        and report the largest node distance between the two results (StepReport
        error_estimate, m; error_estimate_seconds its cost); the state kept is the full step's.
        """
        self._handle = None
        definition = _defs.world_def(gravity, error_estimate)
        handle = ctypes.c_void_p()
        check(lib.sh_world_create(ctypes.byref(definition), ctypes.byref(handle)), "sh_world_create")
        self._handle = handle.value
        self._gravity = tuple(float(g) for g in definition.gravity)

    # -- lifetime --------------------------------------------------------------------------

    def close(self) -> None:
        """Destroy the C world and all its bodies now. Safe to call more than once; later use of
        the world or of its Body objects raises softhap.Error (SH_ERR_INVALID_HANDLE)."""
        OwnedHandle.close(self)

    def __repr__(self) -> str:
        state = "closed" if self._handle is None else "gravity=%r" % (self._gravity,)
        return "<softhap.World %s>" % state

    # -- settings and state ----------------------------------------------------------------

    @property
    def gravity(self) -> Tuple[float, ...]:
        """Gravitational acceleration (m/s^2) as a tuple; assigning calls sh_world_set_gravity."""
        return self._gravity

    @gravity.setter
    def gravity(self, value: ArrayLike) -> None:
        self.set_gravity(value)

    def set_gravity(self, gravity: ArrayLike) -> None:
        """Set the gravitational acceleration (3 floats, m/s^2)."""
        handle = self._require_handle("sh_world_set_gravity")
        gravity = _arrays.float_array(gravity, "gravity", (3,))
        check(lib.sh_world_set_gravity(handle, _arrays.double_ptr(gravity)), "sh_world_set_gravity")
        self._gravity = tuple(float(g) for g in gravity)

    @property
    def warnings(self) -> Dict[str, int]:
        """The world's warning counters as a dict {"SH_WARN_UNSTABLE": count, ...}."""
        handle = self._require_handle("sh_world_get_warnings")
        counters = (ctypes.c_uint64 * SH_WARN_COUNT)()
        check(lib.sh_world_get_warnings(handle, counters), "sh_world_get_warnings")
        return {kind.name: int(counters[int(kind)]) for kind in WarningKind}

    def step(self, dt: float, report: bool = True) -> Optional[StepReport]:
        """Advance every body by dt seconds and return the StepReport (a dict with attribute
        access: wall_seconds, substeps, dt_critical, kinetic_energy, elastic_energy,
        potential_energy, warnings (set of names), warning_bits, unstable_body_count, ...;
        with tools or obstacles: contact_count (contact points at the step's end state),
        collision_seconds and contact_substeps (sub-steps taken so that no tool moves more
        than half its inner radius at once; 1 = none); with cutting: cut_faces (faces cutting
        tools separated), springs_broken (springs torn past their break_strain) and
        topology_seconds).

        If a body's step failed (rejected or rolled back: SH_ERR_UNSTABLE; an implicit body's
        SH_ERR_SOLVER or SH_ERR_NOT_CONVERGED) that body is as before and the other bodies still
        advanced; the raised softhap.Error then carries the step's report as ``err.report``
        (None when nothing was stepped, e.g. for an invalid dt).

        With report=False the step returns None and skips what only the report needs: the
        library then sums no energies (a pass over every element of every body) and Python
        builds no report; the step itself is the same. A failure's err.report is then None.
        """
        handle = self._require_handle("sh_world_step")
        if not report:
            check(lib.sh_world_step(handle, float(dt), None), "sh_world_step")
            return None
        raw = sh_step_report()
        raw.substeps = 0  # sentinel: the library writes >= 1 when it stepped the bodies
        status = lib.sh_world_step(handle, float(dt), ctypes.byref(raw))
        check(status, "sh_world_step",
              report=lambda: step_report(raw) if raw.substeps > 0 else None)
        return step_report(raw)

    def solve_static(
        self,
        tolerance: float = 1e-10,
        max_iterations: int = 50,
        load_steps: int = 1,
        linear_solver: str = "default",
    ) -> StaticReport:
        """Move every body to static equilibrium under gravity and its external forces, fixed
        and prescribed nodes held (sh_world_solve_static); velocities become zero. Returns a
        StaticReport: iterations, load_steps, converged, residual, residual_history (array),
        wall_seconds.

        tolerance: relative residual to reach; max_iterations: Newton iterations per load
        step; load_steps: equal load increments; linear_solver: "default" (CHOLMOD when built
        in, else "ldlt"), "cholmod", "ldlt" or "cg". A body with no fixed node raises
        softhap.Error SH_ERR_SOLVER; an unreached tolerance raises SH_ERR_NOT_CONVERGED. On any
        error every body keeps its previous state, and ``err.report`` is the report of what was
        tried (converged False) when the library filled it (it does not for rejected
        arguments), else None.
        """
        arguments = dict(locals())
        handle = self._require_handle("sh_world_solve_static")
        definition = _defs.static_def(arguments)
        raw = sh_static_report()
        raw.iterations = -1  # sentinel: tells whether the library wrote the report
        status = lib.sh_world_solve_static(handle, ctypes.byref(definition), ctypes.byref(raw))
        check(status, "sh_world_solve_static",
              report=lambda: static_report(raw) if raw.iterations >= 0 else None)
        return static_report(raw)

    # -- bodies ----------------------------------------------------------------------------

    def add_fem_body(
        self,
        mesh: Mesh,
        model: str = "stvk",
        young: float = 3000.0,
        poisson: float = 0.45,
        density: float = 1000.0,
        toughness: float = 200.0,
        integrator: str = "symplectic_euler",
        damping_mass: float = 0.0,
        damping_stiffness: float = 0.0,
        on_unstable: str = "substep",
        runaway_speed: float = 1e4,
        linear_solver: str = "default",
        newton_max_iterations: int = 1,
        newton_tolerance: float = 1e-6,
        cg_tolerance: float = 1e-8,
        cg_max_iterations: int = 2000,
        factor_reuse: float = 0.25,
        max_substeps: int = 16,
    ) -> Body:
        """Add a tetrahedral FEM body whose rest shape is mesh (copied) and return its Body.

        The defaults are those of sh_fem_body_def_default (soft tissue):
          model: "stvk", "linear", "corotational" or "neohookean";
          young: Young's modulus (Pa); poisson: Poisson's ratio; density: kg/m^3;
          toughness: fracture toughness G_c (J/m^2) for cutting tools with
          criterion="physical" (0: never breaks that way);
          integrator: "symplectic_euler", "forward_euler", "rk2", "rk4" or "implicit_euler";
          damping_mass: Rayleigh alpha (1/s); damping_stiffness: Rayleigh beta (s);
          on_unstable: "substep" or "reject": explicit steps above the critical step are
          sub-stepped or rejected; implicit steps that do not converge are retried in up to
          max_substeps sub-steps and then keep their best iterate ("SH_WARN_NOT_CONVERGED" in
          the step report's warnings), or rejected;
          runaway_speed: a node faster than this (m/s) rolls the step back;
          implicit_euler only (sh_implicit_settings): linear_solver "default" (CHOLMOD when
          built in, else "ldlt"), "cholmod", "ldlt" or "cg"; newton_max_iterations (1: one
          linearised solve per step); newton_tolerance; cg_tolerance; cg_max_iterations;
          factor_reuse (0.25: keep a direct solver's factorisation while its updates at least
          halve the residual, a linearised step taking them until the residual is down 4x;
          under large rotation, precondition conjugate gradients on the current tangent with
          it instead of factorising every step; 0 = factorise at every Newton iteration);
          max_substeps.
        Unknown names raise ValueError; invalid values raise softhap.Error
        (SH_ERR_INVALID_ARGUMENT).
        """
        arguments = dict(locals())
        self._require_handle("sh_fem_body_create")
        if not isinstance(mesh, Mesh):
            raise TypeError("mesh must be a softhap.Mesh, got %s" % type(mesh).__name__)
        definition = _defs.fem_body_def(mesh._require_handle("sh_fem_body_create"), arguments)
        return self._add_body("sh_fem_body_create", definition)

    def _add_body(self, function_name: str, definition: ctypes.Structure) -> Body:
        """Call the C function function_name(world, &definition, &id) and return the new Body."""
        body = sh_body_id()
        function = getattr(lib, function_name)
        check(function(self._require_handle(function_name), ctypes.byref(definition), ctypes.byref(body)), function_name)
        return Body(self, body.value)

    def add_spring_body(
        self,
        nodes: Union[ArrayLike, Mesh],
        springs: Optional[ArrayLike] = None,
        law: str = "linear",
        mass: Union[float, ArrayLike] = 1e-3,
        integrator: str = "symplectic_euler",
        on_unstable: str = "substep",
        damping_mass: float = 0.0,
        runaway_speed: float = 1e4,
        stiffness: float = default(100.0),
        damping: float = 0.0,
        lambda1: float = default(0.0),
        lambda2: Optional[float] = None,
        a: float = default(0.0),
        b: Optional[float] = None,
        table: Optional[ArrayLike] = None,
        break_strain: float = 0.0,
        linear_solver: str = "default",
        newton_max_iterations: int = 1,
        newton_tolerance: float = 1e-6,
        cg_tolerance: float = 1e-8,
        cg_max_iterations: int = 2000,
        factor_reuse: float = 0.25,
        max_substeps: int = 16,
    ) -> Body:
        """Add a mass-spring body and return its Body. Rest lengths are the initial lengths.

        nodes: an (n, 3) array of positions (m), or a softhap.Mesh whose nodes are used (and,
            when springs is None, whose edges become the springs).
        springs: an (s, 2) array of node index pairs, or None (no springs for an array of
            nodes: one node and no spring is a particle).
        law and its parameters (only the chosen law's are accepted; the defaults are those of
        sh_spring_body_def_default):
            "linear": stiffness k (N/m);
            "cubic": T = lambda1 d^3 + lambda2 d with d the strain, lambda1, lambda2 (N;
            lambda2 > 0 has no default);
            "hyperbolic": T = dx / (a |dx| + b), a (1/N), b (m/N; b > 0 has no default);
            "table": table, rows of (strain, force N), strain strictly increasing;
            every law also takes damping c (N s/m).
        break_strain: a spring stretched beyond this strain (l / l0 - 1) breaks at the start
            of the next step, and a node left holding pieces joined only through it is split
            (tearing; the step report's springs_broken counts them); 0 = never.
        mass: a scalar mass per node (kg) or an array of n masses.
        integrator, on_unstable, damping_mass (1/s), runaway_speed (m/s) and the implicit
            settings (linear_solver, newton_max_iterations, ...): as add_fem_body.
        Unknown names raise ValueError; invalid values raise softhap.Error.
        """
        arguments = dict(locals())
        self._require_handle("sh_spring_body_create")
        definition, arrays = _defs.spring_body_def(nodes, springs, law, mass, arguments)
        body = self._add_body("sh_spring_body_create", definition)
        del arrays  # the definition pointed into them until the C library copied what it needs
        return body

    def remove_body(self, body: Body) -> None:
        """Destroy body; its id becomes stale (using the Body afterwards raises softhap.Error with
        status SH_ERR_INVALID_HANDLE)."""
        handle = self._require_handle("sh_body_destroy")
        check(lib.sh_body_destroy(handle, body_id_in(self, body, "body")), "sh_body_destroy")

    # -- haptics ----------------------------------------------------------------------------

    def add_haptic(
        self,
        tool: Tool,
        capacity_tets: int = 2000,
        capacity_nodes: int = 2000,
        radius: float = 0.02,
        rings: int = 0,
        dt: float = 1e-3,
        max_force: float = 10.0,
        max_force_rate: float = 2000.0,
        ramp_time: float = 0.05,
        stale_after: float = 0.1,
    ) -> Haptic:
        """Create a haptic context (sh_haptic_create) for tool and return its Haptic. The
        defaults are those of sh_haptic_def_default.

        The buffer holds at most capacity_tets tets and capacity_nodes nodes: those whose
        centroid lies within radius (m) of the tool's nearest surface point (for a capsule,
        box or hull, of the line through it along the tool's length), or, with
        rings > 0, the tets within that many rings of the contact. dt is the nominal haptic
        step (s). The rendered force is at most max_force (N), moves at most max_force_rate
        (N/s) times dt per step, ramps in over ramp_time (s) and ramps out once the full-model
        data is older than stale_after (s of haptic time). Each World.step then moves the tool
        to the latest device pose first and re-extracts the buffer last."""
        options = dict(
            capacity_tets=capacity_tets,
            capacity_nodes=capacity_nodes,
            radius=radius,
            rings=rings,
            dt=dt,
            max_force=max_force,
            max_force_rate=max_force_rate,
            ramp_time=ramp_time,
            stale_after=stale_after,
        )
        return Haptic(self, tool, **options)

"""softhap.World (sh_world) and softhap.Body (an sh_body_id in a world)."""

import ctypes

import numpy as np

from . import _arrays
from ._lib import (
    INTEGRATORS,
    LINEAR_SOLVERS,
    MATERIAL_MODELS,
    SH_WARN_COUNT,
    SHAPE_KINDS,
    SPRING_LAWS,
    UNSTABLE_POLICIES,
    WarningKind,
    sh_body_id,
    sh_body_info,
    sh_collider_def,
    sh_contact_params,
    sh_fem_body_def,
    sh_spring_body_def,
    sh_static_def,
    sh_static_report,
    sh_step_report,
    sh_world_def,
)
from ._entity import WorldEntity
from ._handle import OwnedHandle
from ._loaded import check, lib
from ._record import BodyInfo, StaticReport, StepReport, record_of
from .contact import Obstacle, Tool
from .mesh import Mesh

# Which sh_spring_params fields each law reads (damping is read by every law).
_SPRING_LAW_PARAMETERS = {
    "linear": ("stiffness", "damping"),
    "cubic": ("lambda1", "lambda2", "damping"),
    "hyperbolic": ("a", "b", "damping"),
    "table": ("table", "damping"),
}

# Which sh_shape fields each shape kind reads.
_SHAPE_PARAMETERS = {
    "sphere": ("radius",),
    "capsule": ("radius", "half_length"),
    "box": ("half_extents",),
    "convex": ("points",),
    "plane": ("normal",),
}


def _choose(value, choices, parameter):
    """Map a name such as "rk4" to its C enum value; unknown names raise ValueError."""
    if isinstance(value, str) and value in choices:
        return choices[value]
    raise ValueError(
        "%s must be one of %s, got %r" % (parameter, ", ".join(repr(c) for c in choices), value)
    )


def _warning_names(bits):
    return frozenset(kind.name for kind in WarningKind if bits & (1 << int(kind)))


def _step_report(raw):
    return record_of(StepReport, raw, warnings=_warning_names(raw.warnings), warning_bits=int(raw.warnings))


def _static_report(raw):
    count = max(0, min(int(raw.history_count), len(raw.residual_history)))
    return StaticReport(
        iterations=raw.iterations,
        load_steps=raw.load_steps,
        converged=bool(raw.converged),
        residual=raw.residual,
        residual_history=np.array(raw.residual_history[:count], dtype=np.float64),
        wall_seconds=raw.wall_seconds,
    )


def _choice(choices, parameter):
    """Converter of a name (e.g. "rk4") to its C enum value, for _fill."""
    return lambda value: _choose(value, choices, parameter)


def _int32(parameter):
    """Converter of an integer count, for _fill."""
    return lambda value: _arrays.count(value, parameter)


# For each C struct filled from keyword arguments: field name -> converter.
_MATERIAL_FIELDS = {
    "model": _choice(MATERIAL_MODELS, "model"),
    "young": float,
    "poisson": float,
    "density": float,
}
_BODY_FIELDS = {  # shared by sh_fem_body_def and sh_spring_body_def
    "integrator": _choice(INTEGRATORS, "integrator"),
    "on_unstable": _choice(UNSTABLE_POLICIES, "on_unstable"),
    "damping_mass": float,
    "runaway_speed": float,
}
_IMPLICIT_FIELDS = {
    "linear_solver": _choice(LINEAR_SOLVERS, "linear_solver"),
    "newton_max_iterations": _int32("newton_max_iterations"),
    "newton_tolerance": float,
    "cg_tolerance": float,
    "cg_max_iterations": _int32("cg_max_iterations"),
    "factor_reuse": float,
    "max_substeps": _int32("max_substeps"),
}
_CONTACT_FIELDS = {
    "stiffness": float,
    "exponent": float,
    "damping": float,
    "static_friction": float,
    "dynamic_friction": float,
    "slip_velocity": float,
    "capacity": _int32("capacity"),
}
_STATIC_FIELDS = {
    "tolerance": float,
    "max_iterations": _int32("max_iterations"),
    "load_steps": _int32("load_steps"),
    "linear_solver": _choice(LINEAR_SOLVERS, "linear_solver"),
}


def _fill(struct, fields, arguments):
    """Set each field of struct named in fields from arguments[name] through its converter,
    skipping arguments that are None (they keep the C default)."""
    for name, convert in fields.items():
        value = arguments.get(name)
        if value is not None:
            setattr(struct, name, convert(value))


def _set_body_options(definition, arguments):
    """Fill the options sh_fem_body_def and sh_spring_body_def share (integration and implicit
    settings) from a method's keyword arguments."""
    _fill(definition, _BODY_FIELDS, arguments)
    _fill(definition.implicit, _IMPLICIT_FIELDS, arguments)


def _contact_arguments(arguments):
    """The sh_contact_params keyword arguments of a method, with the shorthand friction=mu
    turned into static_friction = dynamic_friction = mu."""
    arguments = dict(arguments)
    friction = arguments.get("friction")
    if friction is not None:
        for name in ("static_friction", "dynamic_friction"):
            if arguments.get(name) is not None:
                raise ValueError(
                    "friction= sets both static_friction and dynamic_friction; give either "
                    "friction= or %s=, not both" % name
                )
            arguments[name] = friction
    return arguments


def _contact_params(arguments):
    """An sh_contact_params with the C defaults of sh_contact_params_default, the fields named
    in arguments (not None) replaced."""
    params = sh_contact_params()
    lib.sh_contact_params_default(ctypes.byref(params))
    _fill(params, _CONTACT_FIELDS, _contact_arguments(arguments))
    return params


def _collider_def(kind, arguments, position, orientation):
    """An sh_collider_def (C defaults of sh_collider_def_default) of shape kind with the shape
    fields and contact law in arguments, at position and orientation (None keeps the default).
    Returns (def, arrays): arrays must stay alive until the create call returns (the def points
    into them)."""
    definition = sh_collider_def()
    lib.sh_collider_def_default(ctypes.byref(definition))
    shape = definition.shape
    shape.kind = _choose(kind, SHAPE_KINDS, "kind")
    accepted = _SHAPE_PARAMETERS[kind]
    for name in ("radius", "half_length", "half_extents", "points", "normal"):
        if arguments.get(name) is not None and name not in accepted:
            raise ValueError(
                "%s= is not a parameter of a %r shape (it takes: %s)"
                % (name, kind, ", ".join(p + "=" for p in accepted))
            )
    arrays = []
    if arguments.get("radius") is not None:
        shape.radius = float(arguments["radius"])
    if arguments.get("half_length") is not None:
        shape.half_length = float(arguments["half_length"])
    for name in ("half_extents", "normal"):
        if arguments.get(name) is not None:
            value = _arrays.float_array(arguments[name], name, (3,))
            for k in range(3):
                getattr(shape, name)[k] = value[k]
    if arguments.get("points") is not None:
        points = _arrays.float_array(arguments["points"], "points", (None, 3))
        arrays.append(points)
        shape.points = _arrays.double_ptr(points)
        shape.point_count = _arrays.count(points.shape[0], "point count")
    if position is not None:
        position = _arrays.float_array(position, "position", (3,))
        for k in range(3):
            definition.position[k] = position[k]
    if orientation is not None:
        orientation = _arrays.float_array(orientation, "orientation", (4,))
        for k in range(4):
            definition.orientation[k] = orientation[k]
    _fill(definition.contact, _CONTACT_FIELDS, _contact_arguments(arguments))
    return definition, arrays


def _default_material():
    """The material sh_fem_body_def_default chooses (StVK, 3 kPa, 0.45, 1000 kg/m^3)."""
    definition = sh_fem_body_def()
    lib.sh_fem_body_def_default(ctypes.byref(definition))
    return definition.material


class World(OwnedHandle):
    """A simulation world (sh_world): owns bodies and steps them.

    World(gravity=(0, 0, -9.81)) creates one. The C world and all its bodies are freed by
    close(), at the end of a ``with`` block, or when the World is garbage collected (a Body
    keeps its World alive).
    """

    _kind = "world"
    _destroy = "sh_world_destroy"

    def __init__(self, gravity=(0.0, 0.0, -9.81), error_estimate=False):
        """Create a world with the given gravitational acceleration (3 floats, m/s^2).

        error_estimate=True makes every step also take each body over dt in two half steps
        and report the largest node distance between the two results (StepReport
        error_estimate, m; error_estimate_seconds its cost); the state kept is the full step's.
        """
        self._handle = None
        gravity = _arrays.float_array(gravity, "gravity", (3,))
        definition = sh_world_def()
        lib.sh_world_def_default(ctypes.byref(definition))
        for k in range(3):
            definition.gravity[k] = gravity[k]
        definition.error_estimate = 1 if error_estimate else 0
        handle = ctypes.c_void_p()
        check(lib.sh_world_create(ctypes.byref(definition), ctypes.byref(handle)), "sh_world_create")
        self._handle = handle.value
        self._gravity = tuple(float(g) for g in gravity)

    # -- lifetime --------------------------------------------------------------------------

    def close(self):
        """Destroy the C world and all its bodies now. Safe to call more than once; later use of
        the world or of its Body objects raises softhap.Error (SH_ERR_INVALID_HANDLE)."""
        OwnedHandle.close(self)

    def __repr__(self):
        state = "closed" if self._handle is None else "gravity=%r" % (self._gravity,)
        return "<softhap.World %s>" % state

    # -- settings and state ----------------------------------------------------------------

    @property
    def gravity(self):
        """Gravitational acceleration (m/s^2) as a tuple; assigning calls sh_world_set_gravity."""
        return self._gravity

    @gravity.setter
    def gravity(self, value):
        self.set_gravity(value)

    def set_gravity(self, gravity):
        """Set the gravitational acceleration (3 floats, m/s^2)."""
        handle = self._require_handle("sh_world_set_gravity")
        gravity = _arrays.float_array(gravity, "gravity", (3,))
        check(lib.sh_world_set_gravity(handle, _arrays.double_ptr(gravity)), "sh_world_set_gravity")
        self._gravity = tuple(float(g) for g in gravity)

    @property
    def warnings(self):
        """The world's warning counters as a dict {"SH_WARN_UNSTABLE": count, ...}."""
        handle = self._require_handle("sh_world_get_warnings")
        counters = (ctypes.c_uint64 * SH_WARN_COUNT)()
        check(lib.sh_world_get_warnings(handle, counters), "sh_world_get_warnings")
        return {kind.name: int(counters[int(kind)]) for kind in WarningKind}

    def step(self, dt):
        """Advance every body by dt seconds and return the StepReport (a dict with attribute
        access: wall_seconds, substeps, dt_critical, kinetic_energy, elastic_energy,
        potential_energy, warnings (set of names), warning_bits, unstable_body_count, ...;
        with tools or obstacles: contact_count (contact points at the step's end state),
        collision_seconds and contact_substeps (sub-steps taken so that no tool moves more
        than half its inner radius at once; 1 = none)).

        If a body's step failed (rejected or rolled back: SH_ERR_UNSTABLE; an implicit body's
        SH_ERR_SOLVER or SH_ERR_NOT_CONVERGED) that body is as before and the other bodies still
        advanced; the raised softhap.Error then carries the step's report as ``err.report``
        (None when nothing was stepped, e.g. for an invalid dt).
        """
        handle = self._require_handle("sh_world_step")
        raw = sh_step_report()
        raw.substeps = 0  # sentinel: the library writes >= 1 when it stepped the bodies
        status = lib.sh_world_step(handle, float(dt), ctypes.byref(raw))
        check(status, "sh_world_step",
              report=lambda: _step_report(raw) if raw.substeps > 0 else None)
        return _step_report(raw)

    def solve_static(self, tolerance=None, max_iterations=None, load_steps=None, linear_solver=None):
        """Move every body to static equilibrium under gravity and its external forces, fixed
        and prescribed nodes held (sh_world_solve_static); velocities become zero. Returns a
        StaticReport: iterations, load_steps, converged, residual, residual_history (array),
        wall_seconds.

        None keeps the C default of sh_static_def_default: tolerance 1e-10 (relative residual),
        max_iterations 50 (Newton iterations per load step), load_steps 1, linear_solver
        "default". A body with no fixed node raises softhap.Error SH_ERR_SOLVER; an unreached
        tolerance raises SH_ERR_NOT_CONVERGED. On any error every body keeps its previous
        state, and ``err.report`` is the report of what was tried (converged False) when the
        library filled it (it does not for rejected arguments), else None.
        """
        arguments = dict(locals())
        handle = self._require_handle("sh_world_solve_static")
        definition = sh_static_def()
        lib.sh_static_def_default(ctypes.byref(definition))
        _fill(definition, _STATIC_FIELDS, arguments)
        raw = sh_static_report()
        raw.iterations = -1  # sentinel: tells whether the library wrote the report
        status = lib.sh_world_solve_static(handle, ctypes.byref(definition), ctypes.byref(raw))
        check(status, "sh_world_solve_static",
              report=lambda: _static_report(raw) if raw.iterations >= 0 else None)
        return _static_report(raw)

    # -- bodies ----------------------------------------------------------------------------

    def add_fem_body(
        self,
        mesh,
        model=None,
        young=None,
        poisson=None,
        density=None,
        integrator=None,
        damping_mass=None,
        damping_stiffness=None,
        on_unstable=None,
        runaway_speed=None,
        linear_solver=None,
        newton_max_iterations=None,
        newton_tolerance=None,
        cg_tolerance=None,
        cg_max_iterations=None,
        factor_reuse=None,
        max_substeps=None,
    ):
        """Add a tetrahedral FEM body whose rest shape is mesh (copied) and return its Body.

        Arguments left as None keep the C defaults of sh_fem_body_def_default:
          model: "stvk" (default), "linear", "corotational" or "neohookean";
          young: Young's modulus (Pa), default 3000; poisson: Poisson's ratio, default 0.45;
          density: kg/m^3, default 1000;
          integrator: "symplectic_euler" (default), "forward_euler", "rk2", "rk4" or
          "implicit_euler";
          damping_mass: Rayleigh alpha (1/s), default 0; damping_stiffness: Rayleigh beta (s),
          default 0;
          on_unstable: "substep" (default) or "reject": explicit steps above the critical
          step are sub-stepped or rejected; implicit steps that do not converge are retried
          in up to max_substeps sub-steps and then keep their best iterate
          ("SH_WARN_NOT_CONVERGED" in the step report's warnings), or rejected;
          runaway_speed: a node faster than this (m/s) rolls the step back, default 1e4;
          implicit_euler only (sh_implicit_settings): linear_solver "default" (CHOLMOD when
          built in, else "ldlt"), "cholmod", "ldlt" or "cg"; newton_max_iterations (default 1:
          one linearised solve per step); newton_tolerance (default 1e-6); cg_tolerance
          (default 1e-8); cg_max_iterations (default 2000); factor_reuse (default 0.25: keep a
          direct solver's factorisation while its updates at least halve the residual, a
          linearised step taking them until the residual is down 4x; 0 = factorise at every
          Newton iteration); max_substeps (default 16).
        Unknown names raise ValueError; invalid values raise softhap.Error
        (SH_ERR_INVALID_ARGUMENT).
        """
        arguments = dict(locals())
        handle = self._require_handle("sh_world_add_fem_body")
        if not isinstance(mesh, Mesh):
            raise TypeError("mesh must be a softhap.Mesh, got %s" % type(mesh).__name__)
        definition = sh_fem_body_def()
        lib.sh_fem_body_def_default(ctypes.byref(definition))
        definition.mesh = mesh._require_handle("sh_world_add_fem_body")
        _fill(definition.material, _MATERIAL_FIELDS, arguments)
        if damping_stiffness is not None:
            definition.damping_stiffness = float(damping_stiffness)
        _set_body_options(definition, arguments)
        body = sh_body_id()
        check(
            lib.sh_world_add_fem_body(handle, ctypes.byref(definition), ctypes.byref(body)),
            "sh_world_add_fem_body",
        )
        return Body(self, body.value)

    def add_spring_body(
        self,
        nodes,
        springs=None,
        law="linear",
        mass=None,
        integrator=None,
        on_unstable=None,
        damping_mass=None,
        runaway_speed=None,
        stiffness=None,
        damping=None,
        lambda1=None,
        lambda2=None,
        a=None,
        b=None,
        table=None,
        linear_solver=None,
        newton_max_iterations=None,
        newton_tolerance=None,
        cg_tolerance=None,
        cg_max_iterations=None,
        factor_reuse=None,
        max_substeps=None,
    ):
        """Add a mass-spring body and return its Body. Rest lengths are the initial lengths.

        nodes: an (n, 3) array of positions (m), or a softhap.Mesh whose nodes are used (and,
            when springs is None, whose edges become the springs).
        springs: an (s, 2) array of node index pairs, or None (no springs for an array of
            nodes: one node and no spring is a particle).
        law and its parameters (only the chosen law's are accepted; None keeps the C default):
            "linear": stiffness k (N/m, default 100), damping c (N s/m, default 0);
            "cubic": T = lambda1 d^3 + lambda2 d with d the strain, lambda1, lambda2 (N);
            "hyperbolic": T = dx / (a |dx| + b), a (1/N), b (m/N);
            "table": table, rows of (strain, force N), strain strictly increasing;
            every law also takes damping c (N s/m).
        mass: a scalar mass per node (kg, default 1e-3) or an array of n masses.
        integrator, on_unstable, damping_mass (1/s), runaway_speed (m/s) and the implicit
            settings (linear_solver, newton_max_iterations, ...): as add_fem_body.
        Unknown names raise ValueError; invalid values raise softhap.Error.
        """
        arguments = dict(locals())
        handle = self._require_handle("sh_world_add_spring_body")
        definition = sh_spring_body_def()
        lib.sh_spring_body_def_default(ctypes.byref(definition))

        # The arrays the def points into are locals: alive until the create call returns.
        if isinstance(nodes, Mesh):
            definition.mesh = nodes._require_handle("sh_world_add_spring_body")
            node_count = nodes.node_count
        else:
            node_array = _arrays.float_array(nodes, "nodes", (None, 3))
            definition.nodes = _arrays.double_ptr(node_array)
            definition.node_count = _arrays.count(node_array.shape[0], "node count")
            node_count = node_array.shape[0]
        if springs is not None:
            spring_array = _arrays.index_array(springs, "springs", (None, 2))
            definition.springs = _arrays.int32_ptr(spring_array)
            definition.spring_count = _arrays.count(spring_array.shape[0], "spring count")

        definition.params.law = _choose(law, SPRING_LAWS, "law")
        given = {
            "stiffness": stiffness,
            "damping": damping,
            "lambda1": lambda1,
            "lambda2": lambda2,
            "a": a,
            "b": b,
            "table": table,
        }
        accepted = _SPRING_LAW_PARAMETERS[law]
        for name, value in given.items():
            if value is not None and name not in accepted:
                raise ValueError(
                    "%s= is not a parameter of the %r spring law (it takes: %s)"
                    % (name, law, ", ".join(accepted))
                )
        for name in ("stiffness", "damping", "lambda1", "lambda2", "a", "b"):
            if given[name] is not None:
                setattr(definition.params, name, float(given[name]))
        if table is not None:
            table_array = _arrays.float_array(table, "table", (None, 2))
            definition.params.table = _arrays.double_ptr(table_array)
            definition.params.table_rows = _arrays.count(table_array.shape[0], "table rows")

        if mass is not None:
            if np.ndim(mass) == 0:
                definition.node_mass = float(mass)
            else:
                mass_array = _arrays.float_array(mass, "mass", (node_count,))
                definition.node_masses = _arrays.double_ptr(mass_array)
        _set_body_options(definition, arguments)

        body = sh_body_id()
        status = lib.sh_world_add_spring_body(handle, ctypes.byref(definition), ctypes.byref(body))
        check(status, "sh_world_add_spring_body")
        return Body(self, body.value)

    def _own_body(self, body, name):
        if not isinstance(body, Body):
            raise TypeError("%s must be a softhap.Body, got %s" % (name, type(body).__name__))
        if body.world is not self:
            raise ValueError("%r belongs to another world" % (body,))
        return body.id

    # -- tools, obstacles and contact -------------------------------------------------------

    def add_tool(
        self,
        kind,
        radius=None,
        half_length=None,
        half_extents=None,
        points=None,
        position=(0.0, 0.0, 0.0),
        orientation=(1.0, 0.0, 0.0, 0.0),
        stiffness=None,
        exponent=None,
        damping=None,
        static_friction=None,
        dynamic_friction=None,
        slip_velocity=None,
        capacity=None,
        friction=None,
    ):
        """Add a rigid tool posed by the host (sh_tool_create) and return its Tool.

        kind and its shape parameters (only the kind's are accepted; None keeps the C default
        of sh_collider_def_default):
            "sphere": radius (m, default 5 mm), centred on the pose;
            "capsule": radius and half_length (m, default 0) of the segment along local z;
            "box": half_extents, 3 half widths along the local axes (m);
            "convex": points, an (n, 3) array (m, local frame, n >= 4, not all in one plane;
            needs a library built with libccd, else SH_ERR_UNSUPPORTED);
            "plane" is an obstacle only: the C library rejects it as a tool.
        position (m, world) and orientation (unit quaternion (w, x, y, z)): the initial pose.
        The contact law against every body (sh_contact_params; None keeps the C default):
            stiffness lambda (N/m^n, default 1e4), exponent n (default 1.5), damping alpha
            (s/m, default 0.2) of the Hunt-Crossley force F = lambda x^n (1 + 3/2 alpha x');
            static_friction mu_s and dynamic_friction mu_d (default 0; mu_s >= mu_d is
            required, so set both, or use friction=mu for mu_s = mu_d = mu); slip_velocity
            (m/s, default 1e-3) below which friction is viscous; capacity (most contact points
            kept per step, default 4096).
        Unknown names raise ValueError; invalid values raise softhap.Error
        (SH_ERR_INVALID_ARGUMENT, the message naming the field).
        """
        arguments = dict(locals())
        return Tool(self, self._create_collider("sh_tool_create", kind, arguments, position, orientation))

    def add_obstacle(
        self,
        kind,
        point=None,
        normal=None,
        center=None,
        half_extents=None,
        orientation=None,
        radius=None,
        half_length=None,
        points=None,
        stiffness=None,
        exponent=None,
        damping=None,
        static_friction=None,
        dynamic_friction=None,
        slip_velocity=None,
        capacity=None,
        friction=None,
    ):
        """Add a static rigid obstacle (sh_obstacle_create) and return its Obstacle.

        kind and its placement and shape (only the kind's are accepted; None keeps the C
        default of sh_collider_def_default):
            "plane": point (m, default the origin) on the plane and its outward normal
            (default (0, 0, 1)); the obstacle is the half-space behind it;
            "sphere": radius (m, default 5 mm); "capsule": radius and half_length (m) of the
            segment along local z; "box": half_extents (3 half widths, m); "convex": points,
            an (n, 3) array (m, local frame, n >= 4, not all in one plane; needs libccd);
            each with center (m, world, default the origin) and orientation (unit quaternion
            (w, x, y, z), default (1, 0, 0, 0)).
        The contact law (stiffness, exponent, damping, static_friction, dynamic_friction,
        friction, slip_velocity, capacity): as World.add_tool.
        Unknown names raise ValueError; invalid values raise softhap.Error.
        """
        arguments = dict(locals())
        if kind == "plane":
            for name in ("center", "orientation"):
                if arguments[name] is not None:
                    raise ValueError(
                        "%s= is not a parameter of a 'plane' obstacle (it takes: point=, "
                        "normal=)" % name
                    )
            position = point
        else:
            if point is not None:
                raise ValueError(
                    "point= is a parameter of a 'plane' obstacle only; a %r obstacle is placed "
                    "with center= and orientation=" % (kind,)
                )
            position = center
        return Obstacle(
            self, self._create_collider("sh_obstacle_create", kind, arguments, position, orientation)
        )

    def _create_collider(self, function, kind, arguments, position, orientation):
        """The id that C function (sh_tool_create or sh_obstacle_create) gives the collider of
        shape kind, its keyword arguments and its pose."""
        handle = self._require_handle(function)
        definition, arrays = _collider_def(kind, arguments, position, orientation)
        collider = ctypes.c_uint64()
        check(
            getattr(lib, function)(handle, ctypes.byref(definition), ctypes.byref(collider)),
            function,
        )
        del arrays  # the C library has copied the points
        return collider.value

    def add_haptic(
        self,
        tool,
        capacity_tets=None,
        capacity_nodes=None,
        radius=None,
        rings=None,
        dt=None,
        max_force=None,
        max_force_rate=None,
        ramp_time=None,
        stale_after=None,
    ):
        """Create a haptic context (sh_haptic_create) for tool and return its Haptic.

        The buffer holds at most capacity_tets tets (default 2000) and capacity_nodes nodes
        (2000): those whose centroid lies within radius (m, default 0.02) of the tool's nearest
        surface point, or, with rings > 0, the tets within that many rings of the contact. dt
        is the nominal haptic step (s, 1e-3). The rendered force is at most max_force (N, 10),
        moves at most max_force_rate (N/s, 2000) times dt per step, ramps in over ramp_time
        (s, 0.05) and ramps out once the full-model data is older than stale_after (s of
        haptic time, 0.1). None keeps the C default. Each World.step then moves the tool to the
        latest device pose first and re-extracts the buffer last."""
        from .haptic import Haptic

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

    def set_body_contact(
        self,
        body_a,
        body_b,
        stiffness=None,
        exponent=None,
        damping=None,
        static_friction=None,
        dynamic_friction=None,
        slip_velocity=None,
        capacity=None,
        friction=None,
    ):
        """Enable contact between two different FEM bodies of this world with the given
        contact law (sh_world_set_body_contact; keywords as World.add_tool, None keeping the C
        default of sh_contact_params_default); calling it again replaces the law. Each step
        the surface nodes of each body inside the other are pushed out through the other's
        nearest surface triangle. A mass-spring body raises softhap.Error (SH_ERR_UNSUPPORTED).
        """
        arguments = dict(locals())
        handle = self._require_handle("sh_world_set_body_contact")
        a = self._own_body(body_a, "body_a")
        b = self._own_body(body_b, "body_b")
        params = _contact_params(arguments)
        check(
            lib.sh_world_set_body_contact(handle, a, b, ctypes.byref(params)),
            "sh_world_set_body_contact",
        )

    def clear_body_contact(self, body_a, body_b):
        """Disable contact between two bodies (sh_world_set_body_contact with NULL params); a
        pair without contact is left as it is."""
        handle = self._require_handle("sh_world_set_body_contact")
        a = self._own_body(body_a, "body_a")
        b = self._own_body(body_b, "body_b")
        check(lib.sh_world_set_body_contact(handle, a, b, None), "sh_world_set_body_contact")

    # -- removal ------------------------------------------------------------------------------

    def remove_body(self, body):
        """Destroy body; its id becomes stale (using the Body afterwards raises softhap.Error with
        status SH_ERR_INVALID_HANDLE)."""
        handle = self._require_handle("sh_world_remove_body")
        if not isinstance(body, Body):
            raise TypeError("body must be a softhap.Body, got %s" % type(body).__name__)
        if body.world is not self:
            raise ValueError("%r belongs to another world" % (body,))
        check(lib.sh_world_remove_body(handle, body.id), "sh_world_remove_body")


class Body(WorldEntity):
    """A body of a World (an sh_body_id): an FEM body or a mass-spring network.

    Made by World.add_fem_body or World.add_spring_body. The World owns the body's data; a
    Body keeps its World alive. After World.remove_body the id is stale and every call raises
    softhap.Error (SH_ERR_INVALID_HANDLE); so does every call after the World is closed.
    Arrays read from a body are copies.
    """

    _kind = "body"
    _is_valid = "sh_body_is_valid"

    # -- facts ------------------------------------------------------------------------------

    @property
    def info(self):
        """Facts about the body as a BodyInfo (dict with attribute access): node_count,
        element_count, is_fem, fixed_node_count, total_mass (kg), dt_critical (s)."""
        handle = self._world_handle("sh_body_get_info")
        raw = sh_body_info()
        check(lib.sh_body_get_info(handle, self._id, ctypes.byref(raw)), "sh_body_get_info")
        return record_of(BodyInfo, raw, is_fem=bool(raw.is_fem))

    @property
    def node_count(self):
        """Number of nodes (including orphans)."""
        return self.info["node_count"]

    @property
    def critical_dt(self):
        """Critical explicit time step of the body's integrator (s); inf if there is none."""
        return self.info["dt_critical"]

    # -- state ------------------------------------------------------------------------------

    def _read(self, function_name, columns):
        handle = self._world_handle(function_name)
        n = self.node_count
        out = np.empty((n, columns) if columns else (n,), dtype=np.float64)
        check(
            getattr(lib, function_name)(handle, self._id, _arrays.double_ptr(out), out.size),
            function_name,
        )
        return out

    def _node_vectors(self, value, name):
        return _arrays.float_array(value, name, (self.node_count, 3))

    def _write_node_vectors(self, function_name, value, name):
        handle = self._world_handle(function_name)
        array = self._node_vectors(value, name)
        check(
            getattr(lib, function_name)(handle, self._id, _arrays.double_ptr(array), array.shape[0]),
            function_name,
        )

    @property
    def positions(self):
        """Node positions, an (n, 3) array (m). Reading returns a copy; assigning an (n, 3)
        array sets every position (sh_body_set_positions)."""
        return self._read("sh_body_get_positions", 3)

    @positions.setter
    def positions(self, value):
        self._write_node_vectors("sh_body_set_positions", value, "positions")

    @property
    def velocities(self):
        """Node velocities, an (n, 3) array (m/s). Reading returns a copy; assigning an (n, 3)
        array sets every velocity (fixed and orphan nodes keep zero velocity)."""
        return self._read("sh_body_get_velocities", 3)

    @velocities.setter
    def velocities(self, value):
        self._write_node_vectors("sh_body_set_velocities", value, "velocities")

    @property
    def masses(self):
        """A copy of the lumped nodal masses, an (n,) array (kg; 0 for orphan nodes)."""
        return self._read("sh_body_get_masses", 0)

    def elastic_forces(self):
        """Internal elastic nodal forces at the current positions, an (n, 3) array (N)."""
        return self._read("sh_body_get_elastic_forces", 3)

    def elastic_energy(self):
        """Elastic energy stored at the current positions (J)."""
        handle = self._world_handle("sh_body_get_elastic_energy")
        energy = ctypes.c_double()
        check(
            lib.sh_body_get_elastic_energy(handle, self._id, ctypes.byref(energy)),
            "sh_body_get_elastic_energy",
        )
        return energy.value

    # -- boundary conditions and loads ------------------------------------------------------

    def _node_list(self, function_name, indices):
        handle = self._world_handle(function_name)
        nodes = _arrays.index_list(indices, "indices")
        check(
            getattr(lib, function_name)(handle, self._id, _arrays.int32_ptr(nodes), nodes.size),
            function_name,
        )

    def fix_nodes(self, indices):
        """Fix the listed nodes (an int or a sequence of indices) at their current positions."""
        self._node_list("sh_body_fix_nodes", indices)

    def release_nodes(self, indices):
        """Release fixed or prescribed nodes so that they move freely again."""
        self._node_list("sh_body_release_nodes", indices)

    def prescribe_positions(self, indices, positions):
        """Prescribe target positions ((k, 3), m) of k nodes: each moves linearly to its target
        over the next step and is then held there."""
        handle = self._world_handle("sh_body_prescribe_positions")
        nodes = _arrays.index_list(indices, "indices")
        targets = _arrays.float_array(positions, "positions", (nodes.size, 3))
        check(
            lib.sh_body_prescribe_positions(
                handle,
                self._id,
                _arrays.int32_ptr(nodes),
                _arrays.double_ptr(targets),
                nodes.size,
            ),
            "sh_body_prescribe_positions",
        )

    def apply_forces(self, forces):
        """Set external nodal forces ((n, 3), N), held until changed; None clears them."""
        handle = self._world_handle("sh_body_set_external_forces")
        if forces is None:
            status = lib.sh_body_set_external_forces(handle, self._id, None, 0)
        else:
            array = self._node_vectors(forces, "forces")
            status = lib.sh_body_set_external_forces(
                handle, self._id, _arrays.double_ptr(array), array.shape[0]
            )
        check(status, "sh_body_set_external_forces")

    def set_node_damping(self, coefficients):
        """Set per-node viscous damping c_i (1/s): f_i = -c_i m_i v_i, added to the body's mass
        damping. coefficients is a scalar (every node), an (n,) array, or None to clear."""
        handle = self._world_handle("sh_body_set_node_damping")
        if coefficients is None:
            status = lib.sh_body_set_node_damping(handle, self._id, None, 0)
        else:
            n = self.node_count
            if np.ndim(coefficients) == 0:
                array = np.full(n, float(coefficients))
            else:
                array = _arrays.float_array(coefficients, "coefficients", (n,))
            status = lib.sh_body_set_node_damping(handle, self._id, _arrays.double_ptr(array), n)
        check(status, "sh_body_set_node_damping")

    def set_material(self, element_indices, model=None, young=None, poisson=None, density=None):
        """Set the material of the listed elements (a region of an FEM body). Masses are
        recomputed from the new density.

        The C API has no per-element material getter, so a field left as None takes the
        sh_fem_body_def_default value (StVK, 3000 Pa, 0.45, 1000 kg/m^3), not the element's
        current value. Invalid values raise softhap.Error (SH_ERR_INVALID_ARGUMENT).
        """
        arguments = dict(locals())
        handle = self._world_handle("sh_body_set_material")
        elements = _arrays.index_list(element_indices, "element_indices")
        material = _default_material()
        _fill(material, _MATERIAL_FIELDS, arguments)
        check(
            lib.sh_body_set_material(
                handle, self._id, _arrays.int32_ptr(elements), elements.size, ctypes.byref(material)
            ),
            "sh_body_set_material",
        )

    # -- output -----------------------------------------------------------------------------

    def write_vtu(self, path):
        """Write the body's current shape as an ASCII .vtu file (FEM: tets; springs: lines)
        with point data "velocity"."""
        handle = self._world_handle("sh_body_write_vtu")
        check(
            lib.sh_body_write_vtu(handle, self._id, _arrays.path_bytes(path)), "sh_body_write_vtu"
        )

    def remove(self):
        """Remove this body from its world (same as world.remove_body(body))."""
        self._world.remove_body(self)


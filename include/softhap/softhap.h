/*
 * softhap: real-time soft-tissue simulation and haptic force rendering.
 *
 * The one public header. C99. Conventions (see README):
 *  - every fallible function returns sh_status (SH_OK = 0); sh_last_error_message() gives the
 *    detail of the calling thread's last failure;
 *  - lifetimes: sh_X_create makes an object and sh_X_destroy ends it. Objects that stand alone
 *    (sh_mesh, sh_world, sh_haptic) are opaque pointers: sh_X_destroy(pointer). Objects a world
 *    owns (bodies, tools, obstacles) are generation-checked ids, a distinct struct per kind so
 *    that one kind's id does not compile where another's is expected: sh_X_create(world, def,
 *    &id) and sh_X_destroy(world, id). A destroyed or stale pointer or id is
 *    SH_ERR_INVALID_HANDLE, never a crash; an id whose value is 0 is the null id;
 *  - outputs are written through parameters named out_* after the inputs; an output array is
 *    followed by its capacity, counted in the items it holds (nodes, tets, triangles, edges),
 *    the same unit as the counts the matching setters take; a capacity below what is to be
 *    written is SH_ERR_INVALID_ARGUMENT, with nothing written;
 *  - structs passed in whole (every *_def, sh_material, sh_contact_params) are initialised by
 *    their *_default function, then edited: their internal_init cookie tells a struct that was
 *    never initialised (SH_ERR_UNINITIALIZED_DEF);
 *  - units are SI (m, kg, s, N, Pa, N/m), written on every field; vectors are in the world
 *    frame unless said otherwise;
 *  - "Thread:" says which thread may call (sim, haptic, any); "Alloc:" whether it may allocate
 *    on success (a failing sim-thread call may allocate to format its error message).
 */
#ifndef SOFTHAP_H
#define SOFTHAP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* SH_API marks the library's functions: exported while building it (SOFTHAP_BUILDING),
 * imported from the DLL by its users on Windows, nothing for a static build (define
 * SOFTHAP_STATIC when building and using one). */
#if defined(SOFTHAP_STATIC)
#define SH_API
#elif defined(_WIN32) && defined(SOFTHAP_BUILDING)
#define SH_API __declspec(dllexport)
#elif defined(_WIN32)
#define SH_API __declspec(dllimport)
#elif defined(SOFTHAP_BUILDING)
#define SH_API __attribute__((visibility("default")))
#else
#define SH_API
#endif

/** @defgroup sh_api_version Version
 *  The library's version and optional components.
 *  @{ */

/** Major version: incremented on ABI-incompatible changes (from 1.0 on; before it, every
 *  minor version may change the API and ABI: CHANGELOG.md lists what changed). */
#define SH_VERSION_MAJOR 0
/** Minor version: incremented when features are added compatibly (before 1.0: at every
 *  release). */
#define SH_VERSION_MINOR 6
/** Patch version: incremented for fixes. */
#define SH_VERSION_PATCH 0
/** Version this header declares: MAJOR*1000000 + MINOR*1000 + PATCH. */
#define SH_VERSION (SH_VERSION_MAJOR * 1000000 + SH_VERSION_MINOR * 1000 + SH_VERSION_PATCH)

/** Version of the loaded library, in the SH_VERSION encoding. Compare with SH_VERSION.
 *  Thread: any. Alloc: none. */
SH_API int32_t sh_version(void);

/** Optional components a build may include (CMake SOFTHAP_WITH_CHOLMOD, SOFTHAP_WITH_CCD). */
typedef enum sh_feature {
    SH_FEATURE_CHOLMOD = 1, /**< SuiteSparse CHOLMOD sparse Cholesky (implicit and static solves) */
    SH_FEATURE_CCD = 2      /**< libccd convex collision shapes */
} sh_feature;

/** Bit mask of the sh_feature values compiled into the loaded library.
 *  Thread: any. Alloc: none. */
SH_API uint32_t sh_build_features(void);

/** @} */

/** @defgroup sh_api_status Status and errors
 *  Status codes, error messages and warning kinds.
 *  @{ */

/** Result of every fallible call. */
typedef enum sh_status {
    SH_OK = 0,                  /**< success */
    SH_ERR_INVALID_ARGUMENT = 1,/**< a parameter is NULL, out of range or not finite */
    SH_ERR_INVALID_HANDLE = 2,  /**< a NULL, destroyed or stale object pointer or id */
    SH_ERR_UNINITIALIZED_DEF = 3,/**< a def struct not initialised by its *_def_default */
    SH_ERR_OUT_OF_MEMORY = 4,   /**< an allocation failed; nothing was changed */
    SH_ERR_IO = 5,              /**< a file could not be opened, read or written */
    SH_ERR_PARSE = 6,           /**< a file's content is malformed (message names the line) */
    SH_ERR_DEGENERATE_MESH = 7, /**< mesh data is invalid (message names the element or node) */
    SH_ERR_UNSTABLE = 8,        /**< a step was rejected or rolled back: state is unchanged */
    SH_ERR_UNSUPPORTED = 9,     /**< a feature not built in or not available for this object */
    SH_ERR_SOLVER = 10,         /**< a linear solve or factorisation failed */
    SH_ERR_NOT_CONVERGED = 11,  /**< an iterative method did not converge */
    SH_ERR_CAPACITY = 12,       /**< a fixed capacity would be exceeded */
    SH_ERR_BUSY = 13,           /**< the call is not allowed while objects are alive */
    SH_ERR_INTERNAL = 14        /**< an unexpected internal failure (a bug: please report) */
} sh_status;

/** Static, human-readable name of a status code ("SH_ERR_PARSE: ..."). Never NULL.
 *  Thread: any. Alloc: none. */
SH_API const char* sh_status_string(sh_status status);

/** Detail of the calling thread's last failed call (file and line, element, node or parameter).
 *  Empty string if the last call succeeded. Valid until the thread's next softhap call.
 *  Thread: any. Alloc: none. */
SH_API const char* sh_last_error_message(void);

/** Kinds of warnings. Warnings never stop a run; each kind has a counter. */
typedef enum sh_warning {
    SH_WARN_UNSTABLE = 0,       /**< a step was rejected or rolled back as unstable */
    SH_WARN_SUBSTEPPED = 1,     /**< a step was split into sub-steps to stay below dt_crit */
    SH_WARN_INVERTED = 2,       /**< an element had det F <= 0 at a force evaluation of a step
                                     (counted once per step) */
    SH_WARN_CAPACITY = 3,       /**< a fixed capacity clamped a result */
    SH_WARN_FORCE_CLAMPED = 4,  /**< an output force was clamped */
    SH_WARN_LOCKING = 5,        /**< a material with nu > 0.45 was given to linear tets, which
                                     lock (are too stiff) when nearly incompressible */
    SH_WARN_NOT_CONVERGED = 6,  /**< an implicit step's Newton loop missed its tolerance even in
                                     max_substeps sub-steps and kept its best iterate (the lowest
                                     incremental potential it reached) */
    SH_WARN_COUNT = 7           /**< number of warning kinds */
} sh_warning;

/** @} */

/** @defgroup sh_api_memory Memory
 *  The allocator every softhap allocation goes through.
 *  @{ */

/** Host-provided allocator. alloc returns memory aligned to at least `alignment` (a power of
 *  two, at most 64) or NULL; free accepts NULL. */
typedef struct sh_allocator {
    void* (*alloc)(size_t size, size_t alignment, void* user); /**< allocate size bytes */
    void (*free)(void* ptr, void* user);                       /**< release ptr */
    void* user;                                                /**< passed to both */
} sh_allocator;

/** Install the allocator every softhap allocation goes through (NULL restores the default
 *  aligned malloc/free). Returns SH_ERR_BUSY while any softhap object is alive.
 *  Thread: sim (with no other softhap call running). Alloc: none. */
SH_API sh_status sh_set_allocator(const sh_allocator* allocator);

/** Severity of a log message. */
typedef enum sh_log_level {
    SH_LOG_DEBUG = 0,   /**< detail for developers */
    SH_LOG_INFO = 1,    /**< normal but notable: a step split into sub-steps, a mesh repaired */
    SH_LOG_WARNING = 2, /**< the result may not be what was asked: a step rolled back, an
                             implicit step that kept its best iterate, a capacity reached */
    SH_LOG_COUNT = 3    /**< number of levels (not a level) */
} sh_log_level;

/** Receives one log message (a NUL-terminated line without a newline, valid during the call). */
typedef void (*sh_log_fn)(sh_log_level level, const char* message, void* user);

/** Install the function that receives the library's messages (NULL: none, the default). Only
 *  sim-side calls log (sh_world_step, mesh loading, ...); sh_haptic_step never does. Messages
 *  add detail to what statuses and warning counters already say. Returns SH_ERR_BUSY while any
 *  softhap object is alive (install it at start-up, like the allocator).
 *  Thread: sim (with no other softhap call running). Alloc: none. */
SH_API sh_status sh_set_log_callback(sh_log_fn callback, void* user);

/** @} */

/** @defgroup sh_api_mesh Meshes
 *  Immutable tetrahedral meshes: create, load, transform, read.
 *  @{ */

/** An immutable tetrahedral mesh: nodes, tets (reoriented to positive volume) and its outward
 *  surface. Bodies copy what they need; a mesh may be destroyed after a body is made from it. */
typedef struct sh_mesh sh_mesh;

/** Facts about a mesh. */
typedef struct sh_mesh_info {
    int32_t node_count;             /**< nodes, including orphans */
    int32_t tet_count;              /**< tetrahedra */
    int32_t surface_triangle_count; /**< boundary triangles (faces of exactly one tet) */
    int32_t edge_count;             /**< unique tet edges */
    int32_t orphan_node_count;      /**< nodes used by no tet (kept, excluded from dynamics) */
    int32_t reoriented_tet_count;   /**< inverted tets whose orientation was flipped on input */
    int32_t skipped_element_count;  /**< non-tet elements skipped by the loader */
    double bounds_min[3];           /**< axis-aligned bounding box, file units (m) */
    double bounds_max[3];           /**< axis-aligned bounding box, file units (m) */
    double volume;                  /**< total tet volume (m^3) */
} sh_mesh_info;

/** Create a mesh from arrays: nodes are node_count x 3 doubles (m), tets are tet_count x 4
 *  zero-based node indices. Validates: finite coordinates, indices in range, no repeated node
 *  in a tet, no duplicate tet, no zero-volume tet (SH_ERR_DEGENERATE_MESH naming the element);
 *  inverted tets are reoriented and counted. Thread: sim. Alloc: may. */
SH_API sh_status sh_mesh_create(const double* nodes, int32_t node_count, const int32_t* tets,
                                int32_t tet_count, sh_mesh** out_mesh);

/** Load a tetrahedral mesh, format chosen by extension and content: Gmsh .msh (1, 2.2 and 4.1
 *  ASCII), legacy VTK .vtk (ASCII UNSTRUCTURED_GRID), VTK XML .vtu (ascii data), TetGen
 *  .node/.ele (either path; the other is found beside it). Non-tet elements are skipped.
 *  SH_ERR_IO if unreadable, SH_ERR_PARSE naming the line, SH_ERR_DEGENERATE_MESH naming the
 *  element. Thread: sim. Alloc: may. */
SH_API sh_status sh_mesh_load(const char* path, sh_mesh** out_mesh);

/** Create a new mesh whose nodes are scale * x + translation (translation may be NULL), e.g.
 *  scale = 0.01 for a file in centimetres. scale must be finite and > 0.
 *  Thread: sim. Alloc: may. */
SH_API sh_status sh_mesh_transform(const sh_mesh* mesh, double scale, const double translation[3],
                                   sh_mesh** out_mesh);

/** Destroy a mesh. NULL is a no-op returning SH_OK; a destroyed pointer returns
 *  SH_ERR_INVALID_HANDLE. Thread: sim. Alloc: none. */
SH_API sh_status sh_mesh_destroy(sh_mesh* mesh);

/** Fill *out_info. Thread: sim. Alloc: none. */
SH_API sh_status sh_mesh_get_info(const sh_mesh* mesh, sh_mesh_info* out_info);

/** Copy node positions (node_count x 3 doubles, m) into out_nodes, which has room for
 *  capacity nodes. Thread: sim. Alloc: none. */
SH_API sh_status sh_mesh_get_nodes(const sh_mesh* mesh, double* out_nodes, int32_t capacity);

/** Copy tets (tet_count x 4 node indices) into out_tets, which has room for capacity tets.
 *  Thread: sim. Alloc: none. */
SH_API sh_status sh_mesh_get_tets(const sh_mesh* mesh, int32_t* out_tets, int32_t capacity);

/** Copy surface triangles (surface_triangle_count x 3 node indices, counter-clockwise seen
 *  from outside, so normals point outward) into out_triangles, which has room for capacity
 *  triangles. Thread: sim. Alloc: none. */
SH_API sh_status sh_mesh_get_surface_triangles(const sh_mesh* mesh, int32_t* out_triangles,
                                               int32_t capacity);

/** Copy unique edges (edge_count x 2 node indices, smaller first, sorted) into out_edges, which
 *  has room for capacity edges. Thread: sim. Alloc: none. */
SH_API sh_status sh_mesh_get_edges(const sh_mesh* mesh, int32_t* out_edges, int32_t capacity);

/** Write the mesh as VTK XML unstructured grid (ASCII .vtu). Thread: sim. Alloc: may. */
SH_API sh_status sh_mesh_write_vtu(const sh_mesh* mesh, const char* path);

/** @} */

/** @defgroup sh_api_world World
 *  The world: ids, gravity, warnings and the step.
 *  @{ */

/** A simulation world: owns bodies and steps them. */
typedef struct sh_world sh_world;

/** Generation-checked id of a body (FEM or mass-spring). value 0 is the null id; a
 *  destroyed body's id stays invalid, even after its slot serves a new body. */
typedef struct sh_body_id {
    uint64_t value; /**< opaque: slot and generation; 0 for the null id */
} sh_body_id;

/** Generation-checked id of a tool; see sh_body_id. */
typedef struct sh_tool_id {
    uint64_t value; /**< opaque: slot and generation; 0 for the null id */
} sh_tool_id;

/** Generation-checked id of a static obstacle; see sh_body_id. */
typedef struct sh_obstacle_id {
    uint64_t value; /**< opaque: slot and generation; 0 for the null id */
} sh_obstacle_id;

/** Initialiser of a null id of any kind: `sh_body_id body = SH_NULL_ID;`. */
#define SH_NULL_ID {0}

/** 1 if id (of any kind) is the null id, else 0. */
#define SH_ID_IS_NULL(id) ((id).value == 0)

/** 1 if ids a and b (of the same kind) name the same object, else 0. */
#define SH_ID_EQUAL(a, b) ((a).value == (b).value)

/** World definition. Initialise with sh_world_def_default. */
typedef struct sh_world_def {
    uint32_t internal_init; /**< set by sh_world_def_default; do not touch */
    double gravity[3];      /**< gravitational acceleration (m/s^2), default (0, 0, -9.81) */
    int32_t error_estimate; /**< 1: every sh_world_step also takes each body over dt in two
                                 half steps from the same start state and reports how far
                                 apart the two results are (step doubling, see
                                 sh_step_report.error_estimate); the state kept is still the
                                 full step's. About doubles the step's cost. Default 0 (off) */
} sh_world_def;

/** Fill a world def with defaults. Thread: any. Alloc: none. */
SH_API void sh_world_def_default(sh_world_def* def);

/** Create a world. Thread: sim. Alloc: may. */
SH_API sh_status sh_world_create(const sh_world_def* def, sh_world** out_world);

/** Destroy a world and all its bodies. NULL is a no-op returning SH_OK; a destroyed pointer
 *  returns SH_ERR_INVALID_HANDLE. Thread: sim. Alloc: none. */
SH_API sh_status sh_world_destroy(sh_world* world);

/** Set gravity (m/s^2). Thread: sim. Alloc: none. */
SH_API sh_status sh_world_set_gravity(sh_world* world, const double gravity[3]);

/** Read the world's warning counters, one per sh_warning kind (SH_WARN_COUNT values), into
 *  out_counts. Thread: sim. Alloc: none. */
SH_API sh_status sh_world_get_warnings(const sh_world* world, uint64_t out_counts[SH_WARN_COUNT]);

/** What one sh_world_step did and cost. */
typedef struct sh_step_report {
    double wall_seconds;    /**< wall-clock time of the step (s) */
    int32_t substeps;       /**< largest number of sub-steps any body took (1 = none) */
    double dt_critical;     /**< smallest critical explicit step over the bodies (s) */
    double kinetic_energy;  /**< sum of 1/2 m v^2 after the step (J) */
    double elastic_energy;  /**< stored elastic energy after the step (J) */
    double potential_energy;/**< gravitational energy -m g.x after the step (J) */
    uint32_t warnings;      /**< bit (1 << sh_warning) set for each kind raised in this step */
    int32_t unstable_body_count; /**< bodies rejected or rolled back in this step */
    int32_t newton_iterations;   /**< implicit bodies: most Newton iterations of any body */
    int32_t linear_iterations;   /**< implicit bodies: total linear-solver iterations (CG), or
                                      solves (direct) */
    double newton_residual;      /**< implicit bodies: largest final relative residual */
    double factorize_seconds;    /**< implicit bodies: time in sparse factorisations (s) */
    double solve_seconds;        /**< implicit bodies: time in sparse solves (s) */
    int32_t factorizations;      /**< implicit bodies: sparse factorisations in this step (0
                                      when every solve reused a kept factorisation) */
    double error_estimate;       /**< with sh_world_def.error_estimate: the largest distance
                                      (m) of any node between this step and two half steps
                                      from the same start. It estimates the local error of
                                      the step: for a method of order p the full step's error
                                      is about 2^p / (2^p - 1) times it. -1 when off or when a
                                      half step failed */
    double error_estimate_seconds; /**< time spent on the half steps (s), 0 when off */
    int32_t contact_count;       /**< contact points found in this step (tools, obstacles and
                                      body pairs), at the step's end state */
    double collision_seconds;    /**< time in collision detection and contact forces (s) */
    int32_t contact_substeps;    /**< sub-steps taken so that no tool moves more than half
                                      its inner radius per sub-step (1 = none) */
    int32_t cut_faces;           /**< faces that cutting tools separated in this step */
    double topology_seconds;     /**< time in cuts and topology updates in this step (s) */
    int32_t springs_broken;      /**< springs that tore (sh_spring_params.break_strain) at the
                                      start of this step */
} sh_step_report;

/** Advance every body by dt seconds with its own integrator. A body whose step is rejected
 *  (dt above its critical step under SH_UNSTABLE_REJECT) or whose state became non-finite or
 *  runaway is restored to its state before the call; the call then returns SH_ERR_UNSTABLE,
 *  the other bodies still advance, and SH_WARN_UNSTABLE is counted. report may be NULL.
 *  Thread: sim. Alloc: none once the scene is built, for explicit bodies. An implicit body
 *  builds its solver state on its first step (and after fixed nodes change), implicit bodies
 *  that touch each other build their joint system when they first touch, and sparse
 *  factorisations and CG solves allocate inside CHOLMOD and Eigen, outside sh_set_allocator. */
SH_API sh_status sh_world_step(sh_world* world, double dt, sh_step_report* report);

/** @} */

/** @defgroup sh_api_body_defs Body definitions
 *  Integrators, linear solvers, policies and materials shared by body kinds.
 *  @{ */

/** Time integrators. Forward Euler and RK2 have no stable step for an undamped
 *  elastic body: each step multiplies a mode's energy by 1 + (w dt)^2 (forward Euler) or
 *  1 + (w dt)^4 / 4 (RK2), so they drift even below dt_crit unless damping removes more; a
 *  state that runs away is rolled back (SH_ERR_UNSTABLE). Use them for comparison; symplectic
 *  Euler and RK4 are stable below dt_crit. */
typedef enum sh_integrator {
    SH_INTEGRATOR_FORWARD_EULER = 0,   /**< x += dt v, v += dt a (first order) */
    SH_INTEGRATOR_SYMPLECTIC_EULER = 1,/**< v += dt a, x += dt v (first order, symplectic) */
    SH_INTEGRATOR_RK2 = 2,             /**< explicit midpoint (second order) */
    SH_INTEGRATOR_RK4 = 3,             /**< classical Runge-Kutta (fourth order) */
    SH_INTEGRATOR_IMPLICIT_EULER = 4,  /**< backward Euler, linearised per step (Baraff-Witkin)
                                            with optional Newton iterations: unconditionally
                                            stable, first order, dissipative; see
                                            sh_implicit_settings */
    SH_INTEGRATOR_COUNT = 5            /**< number of kinds, not a kind */
} sh_integrator;

/** Sparse linear solvers of the implicit integrator and the static solver. */
typedef enum sh_linear_solver {
    SH_LINEAR_SOLVER_DEFAULT = 0, /**< CHOLMOD when built in, else SH_LINEAR_SOLVER_LDLT */
    SH_LINEAR_SOLVER_CHOLMOD = 1, /**< SuiteSparse CHOLMOD; symbolic analysis reused while the
                                       sparsity pattern is unchanged */
    SH_LINEAR_SOLVER_LDLT = 2,    /**< Eigen's SimplicialLDLT (no extra dependency) */
    SH_LINEAR_SOLVER_CG = 3,      /**< Eigen's conjugate gradient, warm-started from the last
                                       step's solution */
    SH_LINEAR_SOLVER_COUNT = 4    /**< number of kinds, not a kind */
} sh_linear_solver;

/** Settings of the implicit integrator (read only for SH_INTEGRATOR_IMPLICIT_EULER). */
typedef struct sh_implicit_settings {
    sh_linear_solver linear_solver; /**< default SH_LINEAR_SOLVER_DEFAULT */
    int32_t newton_max_iterations;  /**< 1 = one linearised solve per step (default); more =
                                         Newton iterations until newton_tolerance. A body with
                                         contact candidates in a step always iterates (up to
                                         max(20, this)): contacts that switch on within the
                                         step would make a linearised step oscillate. A
                                         linearised step that would raise the mechanical
                                         energy with no work done on the body goes on towards
                                         the step's minimiser (up to 20 iterations) until an
                                         iterate no longer raises it */
    double newton_tolerance;        /**< (dimensionless) stop when the residual |g| <= tol max(|g_0|, dt |f|)
                                         (f: f_ext + m g and the push of tools and other
                                         bodies at its first iterate) or the velocity correction
                                         <= tol max(|v|, dt |g|, 1e-9 m/s); at the iteration
                                         cap (creeping over friction and contact kinks), a last
                                         correction <= tol L / dt is accepted too, L the bodies'
                                         bounding-box diagonal; default 1e-6 */
    double cg_tolerance;            /**< CG relative residual (dimensionless); default 1e-8 */
    int32_t cg_max_iterations;      /**< CG iteration cap; default 2000 */
    double factor_reuse;            /**< (dimensionless) direct solvers (CHOLMOD, LDLT), > 0: the factorisation
                                         of M + dt D + dt^2 K is kept across Newton iterations
                                         and steps. An update solved with a kept factorisation
                                         is accepted if it at least halves the residual |g|
                                         (2-norm and max-norm), else discarded and solved again
                                         with a fresh factorisation at the same state; a
                                         linearised step (newton_max_iterations = 1) takes such
                                         updates until |g| is down by factor_reuse from its
                                         start. Where the tangent drifts from new factorisations
                                         faster than they pay off (large rotations: a
                                         factorisation's updates fail within a step or two), a
                                         step without contact candidates solves its updates
                                         instead by conjugate gradients on the current tangent
                                         preconditioned by the kept factorisation, to a relative
                                         residual of 0.1 factor_reuse, and factorises afresh once
                                         that has cost as much as a factorisation. A body solved
                                         alone with 9,000 free DOF or more and no contact
                                         candidates uses a multigrid cycle instead (the rigid
                                         motions of aggregates of its nodes at rest, warped by
                                         the nodes' rotations) where
                                         that costs less per step than new factorisations, and
                                         keeps it across steps until its nodes settle or it
                                         fails to cut the residual by factor_reuse within 30
                                         iterations or two factorisations' work, whichever is
                                         less (then it sits out 1, 2, 4 ... 64
                                         steps, doubling with each failure in a row, before it
                                         may serve again); changing dt by more than 25 % or the
                                         matrix rebuilds it. These choices weigh work estimated from counts,
                                         never measured time, so that identical runs repeat bit
                                         for bit. Changing dt,
                                         the fixed nodes, a material or node
                                         damping refactorises. 0 = a new factorisation at every
                                         Newton iteration (exact Newton); must be in [0, 1);
                                         default 0.25 */
    int32_t max_substeps;           /**< with on_unstable = SH_UNSTABLE_SUBSTEP: a step whose
                                         Newton loop does not converge (or whose energy runs
                                         away) is retried as 2, 4, ... equal sub-steps up to this
                                         many; if the last still does not converge it keeps its
                                         best iterate and counts SH_WARN_NOT_CONVERGED. 1 = no
                                         retry; >= 1; default 16 */
} sh_implicit_settings;

/** What a step larger than the body's critical step does. */
typedef enum sh_unstable_policy {
    SH_UNSTABLE_REJECT = 0, /**< return SH_ERR_UNSTABLE (explicit, dt above dt_crit) or the
                                 implicit step's error (SH_ERR_NOT_CONVERGED, ...), body state
                                 untouched */
    SH_UNSTABLE_SUBSTEP = 1,/**< explicit: split the step into equal sub-steps below dt_crit;
                                 implicit: retry a step that does not converge in up to
                                 max_substeps sub-steps, then keep the best iterate with
                                 SH_WARN_NOT_CONVERGED (the world always advances) */
    SH_UNSTABLE_POLICY_COUNT = 2 /**< number of kinds, not a kind */
} sh_unstable_policy;

/** Constitutive models for tetrahedral elements. */
typedef enum sh_material_model {
    SH_MATERIAL_LINEAR = 0,       /**< small-strain linear elasticity (not rotation invariant) */
    SH_MATERIAL_STVK = 1,         /**< St. Venant-Kirchhoff on Green-Lagrange strain */
    SH_MATERIAL_COROTATIONAL = 2, /**< linear elasticity in the element's polar rotation frame */
    SH_MATERIAL_NEOHOOKEAN = 3,   /**< stable neo-Hookean (Smith, de Goes, Kim 2018) */
    SH_MATERIAL_COUNT = 4         /**< number of kinds, not a kind */
} sh_material_model;

/** An isotropic material. Initialise with sh_material_default. */
typedef struct sh_material {
    uint32_t internal_init;  /**< set by sh_material_default; do not touch */
    sh_material_model model; /**< constitutive model */
    double young;            /**< Young's modulus E (Pa), > 0 */
    double poisson;          /**< Poisson's ratio nu (dimensionless), in (-1, 0.5) */
    double density;          /**< mass density rho (kg/m^3), > 0 */
    double toughness;        /**< fracture toughness G_c (J/m^2, >= 0): the energy a crack
                                  needs per unit area of new crack, read by cutting tools with
                                  SH_CUT_PHYSICAL; 0 = never breaks that way. Liver about
                                  200, skin 1000-3000 */
} sh_material;

/** Fill a material with the defaults of soft tissue: StVK, E = 3 kPa, nu = 0.45,
 *  rho = 1000 kg/m^3, toughness 200 J/m^2 (liver). Thread: any. Alloc: none. */
SH_API void sh_material_default(sh_material* material);

/** @} */

/** @defgroup sh_api_fem_body FEM bodies
 *  Tetrahedral finite-element bodies.
 *  @{ */

/** Definition of a tetrahedral FEM body. Initialise with sh_fem_body_def_default. */
typedef struct sh_fem_body_def {
    uint32_t internal_init;         /**< set by sh_fem_body_def_default; do not touch */
    const sh_mesh* mesh;            /**< rest shape (copied); required */
    sh_material material;           /**< material of every element (regions: sh_body_set_material) */
    sh_integrator integrator;       /**< default SH_INTEGRATOR_SYMPLECTIC_EULER */
    sh_unstable_policy on_unstable; /**< default SH_UNSTABLE_SUBSTEP */
    double damping_mass;            /**< Rayleigh alpha (1/s): f = -alpha m v; default 0 */
    double damping_stiffness;       /**< Rayleigh beta (s): f = -beta K v; default 0 */
    double runaway_speed;           /**< a node faster than this (m/s) rolls the step back;
                                         default 1e4 */
    sh_implicit_settings implicit;  /**< used with SH_INTEGRATOR_IMPLICIT_EULER */
} sh_fem_body_def;

/** Fill an FEM body def with defaults: sh_material_default's material, symplectic Euler,
 *  sub-stepping. Thread: any. Alloc: none. */
SH_API void sh_fem_body_def_default(sh_fem_body_def* def);

/** Create an FEM body from def; nodes start at the mesh's rest positions at rest. Orphan nodes
 *  keep their index, get no mass and are never integrated. Thread: sim. Alloc: may. */
SH_API sh_status sh_fem_body_create(sh_world* world, const sh_fem_body_def* def,
                                    sh_body_id* out_body);

/** Set the material of the listed elements (a region: capsule, parenchyma, vessel). Masses are
 *  recomputed from the new densities. Thread: sim. Alloc: may. */
SH_API sh_status sh_body_set_material(sh_world* world, sh_body_id body, const int32_t* elements,
                                      int32_t element_count, const sh_material* material);

/** @} */

/** @defgroup sh_api_spring_body Mass-spring bodies
 *  Mass-spring networks.
 *  @{ */

/** Force laws of a spring of rest length l0 and current length l (tension positive). */
typedef enum sh_spring_law {
    SH_SPRING_LINEAR = 0,     /**< T = k (l - l0) */
    SH_SPRING_CUBIC = 1,      /**< T = lambda1 d^3 + lambda2 d, d = (l - l0) / l0 */
    SH_SPRING_HYPERBOLIC = 2, /**< T = dx / (a |dx| + b), dx = l - l0 (saturates at 1/a) */
    SH_SPRING_TABLE = 3,      /**< T = curve(d), monotone cubic through (strain, force) rows */
    SH_SPRING_LAW_COUNT = 4   /**< number of kinds, not a kind */
} sh_spring_law;

/** Parameters of a spring law; only the chosen law's fields are read. */
typedef struct sh_spring_params {
    sh_spring_law law;     /**< the law */
    double stiffness;      /**< linear: k (N/m), > 0 */
    double damping;        /**< every law: c (N s/m), >= 0, force -c dl/dt along the spring */
    double lambda1;        /**< cubic: coefficient of d^3 (N), >= 0 */
    double lambda2;        /**< cubic: coefficient of d (N), > 0 */
    double a;              /**< hyperbolic: 1/a is the saturation force (1/N), >= 0 */
    double b;              /**< hyperbolic: b is the small-strain compliance (m/N), > 0 */
    const double* table;   /**< table: rows of (strain, force N), strain strictly increasing,
                                copied at creation */
    int32_t table_rows;    /**< table: number of rows, >= 2 */
    double break_strain;   /**< every law: a spring stretched beyond this strain (l / l0 - 1,
                                >= 0) breaks at the start of the next step, and a node left
                                holding pieces joined only through it is split (tearing);
                                0 (default) = never breaks */
} sh_spring_params;

/** Definition of a mass-spring body. Initialise with sh_spring_body_def_default. Nodes come
 *  from `nodes` or, if NULL, from `mesh`; springs from `springs` or, if NULL, from the mesh's
 *  edges (or none: a body of one node and no spring is a particle). */
typedef struct sh_spring_body_def {
    uint32_t internal_init;         /**< set by sh_spring_body_def_default; do not touch */
    const double* nodes;            /**< node_count x 3 positions (m), or NULL to use mesh */
    int32_t node_count;             /**< number of nodes in `nodes` */
    const int32_t* springs;         /**< spring_count x 2 node indices, or NULL */
    int32_t spring_count;           /**< number of springs in `springs` */
    const sh_mesh* mesh;            /**< optional: nodes and edge springs from this mesh */
    sh_spring_params params;        /**< law of every spring; default linear k = 100 N/m */
    double node_mass;               /**< mass of each node (kg) if node_masses is NULL */
    const double* node_masses;      /**< optional per-node masses (kg), node_count values */
    sh_integrator integrator;       /**< default SH_INTEGRATOR_SYMPLECTIC_EULER */
    sh_unstable_policy on_unstable; /**< default SH_UNSTABLE_SUBSTEP */
    double damping_mass;            /**< per-node viscous damping alpha (1/s): f = -alpha m v */
    double runaway_speed;           /**< a node faster than this (m/s) rolls back; default 1e4 */
    sh_implicit_settings implicit;  /**< used with SH_INTEGRATOR_IMPLICIT_EULER */
} sh_spring_body_def;

/** Fill a spring body def with defaults: linear springs k = 100 N/m, c = 0, node mass 1 g,
 *  symplectic Euler, sub-stepping. Thread: any. Alloc: none. */
SH_API void sh_spring_body_def_default(sh_spring_body_def* def);

/** Create a mass-spring body from def; rest lengths are the initial lengths. A spring of zero
 *  rest length, a repeated node or a non-positive mass is SH_ERR_INVALID_ARGUMENT naming it.
 *  Thread: sim. Alloc: may. */
SH_API sh_status sh_spring_body_create(sh_world* world, const sh_spring_body_def* def,
                                       sh_body_id* out_body);

/** @} */

/** @defgroup sh_api_body Body state
 *  Reading and setting a body's state, boundary conditions and loads.
 *  @{ */

/** Facts about a body. */
typedef struct sh_body_info {
    int32_t node_count;     /**< nodes (including orphans) */
    int32_t element_count;  /**< tets (FEM) or springs (mass-spring) */
    int32_t is_fem;         /**< 1 for an FEM body, 0 for a mass-spring body */
    int32_t fixed_node_count; /**< nodes fixed or prescribed */
    double total_mass;      /**< sum of nodal masses (kg) */
    double dt_critical;     /**< critical explicit step of its integrator (s); INFINITY if none */
    int32_t surface_triangle_count; /**< FEM: boundary triangles of the current topology (0 for
                                         mass-spring bodies) */
    int32_t reserved;       /**< 0 */
    uint64_t topology_version; /**< 0 at creation; increases at every topology change (a cut,
                                    springs breaking): re-read tets, surface and node count */
} sh_body_info;

/** Destroy a body (FEM or mass-spring); its id becomes stale, and its contacts with other
 *  bodies end. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_destroy(sh_world* world, sh_body_id body);

/** 1 if body is a live body of world, else 0. Thread: sim. Alloc: none. */
SH_API int32_t sh_body_is_valid(const sh_world* world, sh_body_id body);

/** Fill *out_info. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_get_info(const sh_world* world, sh_body_id body, sh_body_info* out_info);

/** Copy positions (node_count x 3, m) into out_positions, which has room for capacity nodes.
 *  Thread: sim. Alloc: none. */
SH_API sh_status sh_body_get_positions(const sh_world* world, sh_body_id body,
                                       double* out_positions, int32_t capacity);

/** Set all positions (node_count x 3, m). Must be finite. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_set_positions(sh_world* world, sh_body_id body, const double* positions,
                                       int32_t node_count);

/** Copy velocities (node_count x 3, m/s) into out_velocities, which has room for capacity
 *  nodes. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_get_velocities(const sh_world* world, sh_body_id body,
                                        double* out_velocities, int32_t capacity);

/** Set all velocities (node_count x 3, m/s). Must be finite; fixed and orphan nodes keep
 *  zero velocity. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_set_velocities(sh_world* world, sh_body_id body,
                                        const double* velocities, int32_t node_count);

/** Copy lumped nodal masses (node_count values, kg; 0 for orphans) into out_masses, which has
 *  room for capacity nodes. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_get_masses(const sh_world* world, sh_body_id body, double* out_masses,
                                    int32_t capacity);

/** Fix nodes at their current positions (velocity zero). Thread: sim. Alloc: none. */
SH_API sh_status sh_body_fix_nodes(sh_world* world, sh_body_id body, const int32_t* nodes,
                                   int32_t count);

/** Release fixed or prescribed nodes: they move freely again. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_release_nodes(sh_world* world, sh_body_id body, const int32_t* nodes,
                                       int32_t count);

/** Prescribe positions (count x 3, m) of nodes: each is moved linearly to its target over the
 *  next step and then held there (a kinematic boundary condition). Thread: sim. Alloc: none. */
SH_API sh_status sh_body_prescribe_positions(sh_world* world, sh_body_id body,
                                             const int32_t* nodes, const double* positions,
                                             int32_t count);

/** Set external nodal forces (node_count x 3, N), held until changed; NULL clears them.
 *  Thread: sim. Alloc: none. */
SH_API sh_status sh_body_set_external_forces(sh_world* world, sh_body_id body,
                                             const double* forces, int32_t node_count);

/** Set per-node viscous damping coefficients (node_count, 1/s): f_i = -c_i m_i v_i, added to
 *  the body's mass damping; NULL clears. Thread: sim. Alloc: may (first call). */
SH_API sh_status sh_body_set_node_damping(sh_world* world, sh_body_id body,
                                          const double* coefficients, int32_t node_count);

/** Copy the internal elastic nodal forces at the current positions (node_count x 3, N) into
 *  out_forces, which has room for capacity nodes. Thread: sim. Alloc: none. */
SH_API sh_status sh_body_get_elastic_forces(const sh_world* world, sh_body_id body,
                                            double* out_forces, int32_t capacity);

/** Elastic energy stored at the current positions (J). Thread: sim. Alloc: none. */
SH_API sh_status sh_body_get_elastic_energy(const sh_world* world, sh_body_id body,
                                            double* out_energy);

/** Write the body's current shape as ASCII .vtu (FEM: tets; springs: lines) with point data
 *  "velocity". Thread: sim. Alloc: may. */
SH_API sh_status sh_body_write_vtu(const sh_world* world, sh_body_id body, const char* path);

/** @} */

/** @defgroup sh_api_cut Cutting and topology
 *  Cuts separate material, never delete it: the tets on the two sides of a cut surface stop
 *  sharing nodes. Nodes on the cut are copied (each copy appended, with its parent's index),
 *  tets the surface crosses are split so that the new surface follows it, and parts left joined
 *  only through a node are separated too. Node indices never change; a cut body stays one body
 *  (cut through, it has several connected pieces). Thread: sim for everything here.
 *  @{ */

/** What one cut did. */
typedef struct sh_cut_report {
    int32_t faces_separated; /**< tet faces that became surface (counted once per pair of
                                  faces that parted) */
    int32_t nodes_added;     /**< nodes appended: points made on cut edges and node copies */
    int32_t tets_added;      /**< tets after the cut minus tets before */
    int32_t nodes_moved;     /**< existing nodes moved onto the cut surface (0: nodes near the
                                  surface are cut through where they are) */
    double min_quality;      /**< lowest shape quality 6 sqrt(2) V / l_rms^3 of the tets the
                                  cut made (1 regular, 0 flat); 1 if it made none */
    double seconds;          /**< wall time of the cut, topology update included (s) */
    int32_t springs_cut;     /**< mass-spring bodies: springs the surface crossed, removed */
    int32_t reserved;        /**< 0 */
} sh_cut_report;

/** Cut body along a surface: triangle_count triangles, 9 doubles each (three corners, world
 *  frame, m), in the body's current configuration; the triangles need not be welded or
 *  consistently oriented. The material the surface passes through separates; where its
 *  border lies inside the body, the body stays joined (a later cut extends it). An FEM body
 *  keeps its cuts (the last 512 triangles, in its rest shape, so they stay with the material)
 *  and cuts a later one together with those it continues (within 30 degrees of its plane, not
 *  lying on it): cuts that each cross only part of an element, as a scripted blade advancing
 *  by less than an element per call makes, add up; a later cut is then mapped to the rest
 *  shape by its corners (the first is exact in the current configuration). FEM bodies
 *  split every edge it crosses at the crossing (a crossing within a quarter of an edge of a
 *  node, or one that would make a piece of quality below 0.05 or stiffer than 0.3 of the uncut
 *  body's critical step allows, goes through a node instead); mass-spring bodies lose the
 *  springs it crosses. Masses, rest shapes,
 *  the surface, contact, implicit solver data and haptic buffers follow; topology_version
 *  increases if anything was cut. out_report may be NULL. Non-finite coordinates, a
 *  zero-area triangle or triangle_count < 1 are SH_ERR_INVALID_ARGUMENT naming the triangle;
 *  a failed allocation is SH_ERR_OUT_OF_MEMORY; either leaves the body as it was.
 *  Alloc: may. */
SH_API sh_status sh_body_cut(sh_world* world, sh_body_id body, const double* triangles,
                             int32_t triangle_count, sh_cut_report* out_report);

/** When a cutting tool breaks the material its blade reaches. */
typedef enum sh_cut_criterion {
    SH_CUT_GEOMETRIC = 0,  /**< the blade separates whatever its edge sweeps through */
    SH_CUT_PHYSICAL = 1,   /**< the blade's edge holds the material just ahead of it and drags
                                it along; the material breaks one resolution ahead once the
                                work the blade did since the last break pays for that crack:
                                toughness / sharpness times the engaged length times the
                                resolution (an energy balance, Griffith's) */
    SH_CUT_CRITERION_COUNT = 2 /**< number of criteria, not a criterion */
} sh_cut_criterion;

/** How a tool cuts. */
typedef struct sh_cut_def {
    uint32_t internal_init;      /**< set by sh_cut_def_default; do not touch */
    sh_cut_criterion criterion;  /**< default SH_CUT_GEOMETRIC */
    double edge[2][3];           /**< the blade's cutting edge: two points in the tool's local
                                      frame (m), distinct; default (0, 0, -5 mm) to (0, 0, 5 mm) */
    double sharpness;            /**< blade sharpness kappa (dimensionless, > 0; 1 = a scalpel),
                                      for criteria that weigh it; default 1 */
    double resolution;           /**< edge length (m, >= 0) the material is refined to around
                                      the blade's edge and the path of its ends before it cuts,
                                      so that the opening reaches to within about this of the
                                      blade on a coarse mesh (a cut parts whole tet faces);
                                      0 (default) = a quarter of the blade's length; a length
                                      above the mesh's elements refines nothing */
} sh_cut_def;

/** Fill a cut def with defaults. Thread: any. Alloc: none. */
SH_API void sh_cut_def_default(sh_cut_def* def);

/** Make tool a cutting tool with def, or an ordinary one again with NULL (which lets go any
 *  material its edge holds). At every sh_world_step, before the bodies move: with
 *  SH_CUT_GEOMETRIC the surface the blade edge sweeps from the tool's last pose to its new
 *  pose cuts every body it passes through (as sh_body_cut would), so a blade that has entered
 *  the material separates it as it advances, and a cut continues from where the last step's
 *  ended; with SH_CUT_PHYSICAL the edge holds the FEM material just ahead of it (those nodes
 *  move with the blade's motion across the edge, as prescribed nodes) and the material breaks
 *  one resolution beyond the crack's front once the work the blade did on it since the last
 *  break reaches material.toughness / sharpness x engaged length x resolution; the held
 *  material's reaction joins the tool's (sh_tool_get_wrench). The tool's shape still touches
 *  the material through contact. A def not from sh_cut_def_default, coincident edge points or
 *  non-finite values are SH_ERR_INVALID_ARGUMENT. Thread: sim. Alloc: may. */
SH_API sh_status sh_tool_set_cutting(sh_world* world, sh_tool_id tool, const sh_cut_def* def);

/** Copy the FEM body's tets (element_count x 4 node indices, positively oriented) into
 *  out_tets, which has room for capacity tets. SH_ERR_UNSUPPORTED for a mass-spring body.
 *  Alloc: none. */
SH_API sh_status sh_body_get_tets(const sh_world* world, sh_body_id body, int32_t* out_tets,
                                  int32_t capacity);

/** Copy the body's springs (element_count x 2 node indices) into out_springs, which has room
 *  for capacity springs. SH_ERR_UNSUPPORTED for an FEM body. Alloc: none. */
SH_API sh_status sh_body_get_springs(const sh_world* world, sh_body_id body, int32_t* out_springs,
                                     int32_t capacity);

/** Copy the FEM body's boundary triangles (surface_triangle_count x 3 node indices, counter-
 *  clockwise seen from outside) into out_triangles, room for capacity triangles.
 *  SH_ERR_UNSUPPORTED for a mass-spring body. Alloc: none. */
SH_API sh_status sh_body_get_surface_triangles(const sh_world* world, sh_body_id body,
                                               int32_t* out_triangles, int32_t capacity);

/** Copy each node's parent (node_count values: the node it was made from by a cut, -1 for the
 *  body's own nodes) into out_parents, room for capacity nodes. A copy's parent is the node
 *  copied; a node made on a cut edge has the edge's nearer end, and one a cutting tool's
 *  refinement makes at an edge's midpoint has the edge's lower-numbered end. Alloc: none. */
SH_API sh_status sh_body_get_node_parents(const sh_world* world, sh_body_id body,
                                          int32_t* out_parents, int32_t capacity);

/** @} */

/** @defgroup sh_api_contact Tools, obstacles and contact
 *  Rigid tools posed by the host, static obstacles and the contact law.
 *  @{ */

/** Kinds of rigid collision shape. */
typedef enum sh_shape_kind {
    SH_SHAPE_SPHERE = 0,  /**< radius, centred on the pose */
    SH_SHAPE_CAPSULE = 1, /**< radius around the segment from -half_length to +half_length on
                               the local z axis */
    SH_SHAPE_BOX = 2,     /**< half_extents along the local axes, centred on the pose; between
                               a body's nodes its contact takes its largest inscribed capsule
                               along its longest axis (edges and corners sink until it meets
                               the face) */
    SH_SHAPE_CONVEX = 3,  /**< the convex hull of points (local frame); needs SH_FEATURE_CCD;
                               between nodes, as a box: its largest inscribed capsule along
                               its points' principal axis */
    SH_SHAPE_PLANE = 4,   /**< obstacles only: the half-space behind the plane through the
                               pose's position with outward normal `normal` (world frame) */
    SH_SHAPE_COUNT = 5    /**< number of kinds, not a kind */
} sh_shape_kind;

/** A rigid shape. Only the kind's fields are read. */
typedef struct sh_shape {
    sh_shape_kind kind;      /**< the kind; default SH_SHAPE_SPHERE */
    double radius;           /**< sphere, capsule: radius (m), > 0; default 5 mm */
    double half_length;      /**< capsule: half the segment's length (m), >= 0 and at most
                                  1024 radii (its contact takes a ball every half radius) */
    double half_extents[3];  /**< box: half widths along local x, y, z (m), each > 0 */
    const double* points;    /**< convex: point_count x 3 points (m, local frame), not all in
                                  one plane; copied at creation */
    int32_t point_count;     /**< convex: number of points, >= 4 */
    double normal[3];        /**< plane: outward normal (world frame, normalised at creation);
                                  default (0, 0, 1) */
} sh_shape;

/** The nonlinear Hunt-Crossley penalty law and Coulomb friction of a contact. With
 *  penetration depth x >= 0 (m) and its rate x' (m/s), the normal force on the body is
 *  F = max(0, lambda x^n + mu x' x^n) with mu = 3/2 alpha lambda: never attractive and exactly 0
 *  at x = 0; for small alpha v the restitution of an impact at speed v is about 1 - alpha v.
 *  Friction opposes tangential sliding with at most mu_s F while sticking and mu_d F while
 *  sliding, regularised below slip_velocity: a sticking contact creeps at slip_velocity times
 *  its tangential load over mu_s F (below slip_velocity), whatever the time step. Explicit
 *  bodies take friction implicitly on each (sub)step's new velocities (stable at any step);
 *  implicit bodies take it proportional to the normal force at the step's start (so a contact
 *  that begins within a step has no friction until the next). */
typedef struct sh_contact_params {
    uint32_t internal_init;  /**< set by sh_contact_params_default; do not touch */
    double stiffness;        /**< lambda (N/m^n) per contact point, > 0; default 1e4 */
    double exponent;         /**< n (dimensionless), >= 1; default 1.5 (Hertz-like) */
    double damping;          /**< alpha (s/m), >= 0; default 0.2 */
    double static_friction;  /**< mu_s (dimensionless), >= dynamic_friction; default 0 */
    double dynamic_friction; /**< mu_d (dimensionless), >= 0; default 0 */
    double slip_velocity;    /**< tangential speed (m/s) below which friction is viscous
                                  (sticking), > 0; default 1e-3 */
    int32_t capacity;        /**< most contact points kept per step; beyond it the deepest are
                                  kept and SH_WARN_CAPACITY is counted; default 4096 */
} sh_contact_params;

/** Fill contact params with defaults (the values above). Thread: any. Alloc: none. */
SH_API void sh_contact_params_default(sh_contact_params* params);

/** Definition of a tool or an obstacle. Initialise with sh_collider_def_default. */
typedef struct sh_collider_def {
    uint32_t internal_init;    /**< set by sh_collider_def_default; do not touch */
    sh_shape shape;            /**< the shape; default a sphere of radius 5 mm */
    double position[3];        /**< initial position (m, world); a plane passes through it */
    double orientation[4];     /**< initial orientation, unit quaternion (w, x, y, z);
                                  default (1, 0, 0, 0) */
    sh_contact_params contact; /**< the contact law against every body */
} sh_collider_def;

/** Fill a collider def with defaults. Thread: any. Alloc: none. */
SH_API void sh_collider_def_default(sh_collider_def* def);

/** Add a rigid tool posed by the host. A world builds collision structures (surface bounding
 *  volume hierarchies) only once it has a tool or an obstacle. A plane is not a tool
 *  (SH_ERR_INVALID_ARGUMENT); zero-size, non-finite or flat shapes are SH_ERR_INVALID_ARGUMENT
 *  naming the field; a convex shape without libccd is SH_ERR_UNSUPPORTED.
 *  Thread: sim. Alloc: may. */
SH_API sh_status sh_tool_create(sh_world* world, const sh_collider_def* def, sh_tool_id* out_tool);

/** Remove a tool; its id becomes stale. Thread: sim. Alloc: none. */
SH_API sh_status sh_tool_destroy(sh_world* world, sh_tool_id tool);

/** 1 if tool is a live tool of world, else 0. Thread: sim. Alloc: none. */
SH_API int32_t sh_tool_is_valid(const sh_world* world, sh_tool_id tool);

/** Read the pose the next step takes the tool to (the last one set): position (m) and unit
 *  quaternion (w, x, y, z). Thread: sim. Alloc: none. */
SH_API sh_status sh_tool_get_pose(const sh_world* world, sh_tool_id tool,
                                  double out_position[3], double out_orientation[4]);

/** Pose the tool for the next sh_world_step: the step moves it from its last pose to this
 *  one (its velocity is the difference over dt unless set with sh_tool_set_velocity). A
 *  non-finite position or a quaternion that is not finite or is zero is
 *  SH_ERR_INVALID_ARGUMENT and the tool keeps its pose; the quaternion is normalised.
 *  Thread: sim. Alloc: none. */
SH_API sh_status sh_tool_set_pose(sh_world* world, sh_tool_id tool, const double position[3],
                                  const double orientation[4]);

/** Give the tool's velocity for the next step instead of deriving it from successive poses:
 *  linear (m/s) of its position and angular (rad/s), world frame. Only the contact's damping
 *  and friction see it. Thread: sim. Alloc: none. */
SH_API sh_status sh_tool_set_velocity(sh_world* world, sh_tool_id tool, const double linear[3],
                                      const double angular[3]);

/** Contact state of a tool or obstacle after the last step. */
typedef struct sh_contact_state {
    double force[3];            /**< reaction force on the tool/obstacle (N, world frame) */
    double torque[3];           /**< reaction torque about its position (N m, world frame) */
    int32_t contact_count;      /**< contact points in the last step */
    double max_depth;           /**< deepest penetration (m) */
    double penetration_volume;  /**< volume of body material inside the shape (m^3),
                                     approximated as the sum over touching surface nodes of
                                     depth times the node's share of surface area */
} sh_contact_state;

/** Read a tool's reaction wrench (force and torque on the tool, world frame) and contact
 *  measures after the last step, at the step's end state. Thread: sim. Alloc: none. */
SH_API sh_status sh_tool_get_contact(const sh_world* world, sh_tool_id tool,
                                     sh_contact_state* out_state);

/** Read only the reaction wrench of sh_tool_get_contact: force (N) and torque about the tool's
 *  position (N m) on the tool, world frame. Thread: sim. Alloc: none. */
SH_API sh_status sh_tool_get_wrench(const sh_world* world, sh_tool_id tool,
                                    double out_force[3], double out_torque[3]);

/** Add a static rigid obstacle (any shape kind; a plane takes position and shape.normal).
 *  Same validation as sh_tool_create. Thread: sim. Alloc: may. */
SH_API sh_status sh_obstacle_create(sh_world* world, const sh_collider_def* def,
                                    sh_obstacle_id* out_obstacle);

/** Remove an obstacle; its id becomes stale. Thread: sim. Alloc: none. */
SH_API sh_status sh_obstacle_destroy(sh_world* world, sh_obstacle_id obstacle);

/** 1 if obstacle is a live obstacle of world, else 0. Thread: sim. Alloc: none. */
SH_API int32_t sh_obstacle_is_valid(const sh_world* world, sh_obstacle_id obstacle);

/** Read an obstacle's reaction wrench and contact measures after the last step.
 *  Thread: sim. Alloc: none. */
SH_API sh_status sh_obstacle_get_contact(const sh_world* world, sh_obstacle_id obstacle,
                                         sh_contact_state* out_state);

/** Enable contact between two deformable bodies with params (NULL disables it): each step,
 *  the surface nodes of each body that lie inside the other's tets, or in front of its
 *  surface within the distance the two may close in the step, are contact candidates; one
 *  inside is pushed out through the other's nearest surface triangle, the reaction spread over
 *  that triangle's nodes. Both bodies must be FEM bodies of world, and different.
 *  Implicit bodies with candidates between them (directly or through other bodies) are
 *  stepped together: one Newton loop on their joint residual over one sparse system of all
 *  their free nodes, each contact's blocks between the two bodies included, its updates
 *  backtracking until the step's incremental potential or the residual falls; if it fails,
 *  each of them is restored. sh_world_solve_static solves bodies in contact for their joint
 *  equilibrium the same way: one of them needs fixed or prescribed nodes, the others may be
 *  held by their contacts alone, but frictionless contact gives no sideways stiffness, so a
 *  body resting on another needs a sideways hold (or it has no equilibrium to converge to).
 *  A body with an explicit integrator is stepped against the other's latest state
 *  (staggered). Thread: sim. Alloc: may; the joint system of bodies in contact is built when
 *  they first touch and rebuilt when the nodes in contact outgrow it. */
SH_API sh_status sh_world_set_body_contact(sh_world* world, sh_body_id a, sh_body_id b,
                                           const sh_contact_params* params);

/** @} */

/** @defgroup sh_api_static Static equilibrium
 *  Newton-Raphson statics of every body.
 *  @{ */

/** Number of residuals kept in sh_static_report.residual_history. */
#define SH_STATIC_HISTORY 64

/** Settings of sh_world_solve_static. Initialise with sh_static_def_default. */
typedef struct sh_static_def {
    uint32_t internal_init;         /**< set by sh_static_def_default; do not touch */
    double tolerance;               /**< (dimensionless) stop when |residual| / |applied load|
                                         is below this or below the round-off of the internal
                                         forces; default 1e-10 */
    int32_t max_iterations;         /**< Newton iterations per load step; default 50 */
    int32_t load_steps;             /**< apply the loads in this many equal increments;
                                         default 1 */
    sh_linear_solver linear_solver; /**< default SH_LINEAR_SOLVER_DEFAULT */
} sh_static_def;

/** Fill a static def with defaults. Thread: any. Alloc: none. */
SH_API void sh_static_def_default(sh_static_def* def);

/** What sh_world_solve_static did. */
typedef struct sh_static_report {
    int32_t iterations;       /**< Newton iterations over all bodies and load steps */
    int32_t load_steps;       /**< load steps taken */
    int32_t converged;        /**< 1 if every body reached the tolerance */
    int32_t history_count;    /**< entries in residual_history */
    double residual;          /**< final largest relative residual */
    double residual_history[SH_STATIC_HISTORY]; /**< relative residual after each iteration */
    double wall_seconds;      /**< wall-clock time (s) */
} sh_static_report;

/** Move every body to static equilibrium under gravity (lumped, rho g V / 4 per node per tet
 *  for FEM bodies) and its external forces, with fixed and prescribed nodes held: Newton-Raphson
 *  K(x_i) dx = f_ext + f(x_i) with backtracking line search on the potential energy, one sparse
 *  solve for linear materials. Bodies in contact with each other (sh_world_set_body_contact)
 *  are solved together, for their joint equilibrium. Positions are updated in place and
 *  velocities zeroed. A body with no fixed node that no contact holds (singular K) is
 *  SH_ERR_SOLVER; SH_ERR_NOT_CONVERGED if the tolerance is
 *  not reached; on any error every body keeps its previous state and report (if not NULL)
 *  still tells what was tried (converged = 0). Haptic contexts move their tool to the newest
 *  device pose first and restart from the equilibrium after a successful solve.
 *  Thread: sim. Alloc: may. */
SH_API sh_status sh_world_solve_static(sh_world* world, const sh_static_def* def,
                                       sh_static_report* report);

/** @} */

/** @defgroup sh_api_haptic Haptic rendering
 *  The Volumetric Buffer Model stepped on the device thread.
 *  @{ */

/** A haptic context: a small local explicit FEM model (the Volumetric Buffer Model of
 *  Mendoza & Laugier 2003) around a tool's contact, stepped by sh_haptic_step on the device
 *  thread at 1-10 kHz in memory fixed at creation, while sh_world_step on the sim thread
 *  re-extracts it from the full model. Opaque. */
typedef struct sh_haptic sh_haptic;

/** Definition of a haptic context. Initialise with sh_haptic_def_default. */
typedef struct sh_haptic_def {
    uint32_t internal_init;   /**< set by sh_haptic_def_default; do not touch */
    sh_tool_id tool;          /**< the tool the device moves; required. A convex tool's
                                   depth comes from libccd's MPR only in the haptic step
                                   (allocation-free; an upper bound on the depth) */
    int32_t capacity_tets;    /**< most tets in the buffer, >= 1; default 2000 */
    int32_t capacity_nodes;   /**< most nodes in the buffer, >= 4; default 2000 */
    double radius;            /**< buffer radius (m): tets whose centroid lies within it of the
                                   contact point (for a capsule, box or hull, of the line
                                   through it along the tool's length); > 0; default 0.02 */
    int32_t rings;            /**< > 0: instead of radius, the tets within this many rings
                                   (tets sharing a node) of the tets at the contact; default 0 */
    double dt;                /**< nominal haptic step (s), > 0; default 1e-3 */
    double max_force;         /**< largest force output (N), > 0; default 10 */
    double max_force_rate;    /**< largest change of the force output (N/s), > 0; the output
                                   moves at most max_force_rate * dt per step; default 2000 */
    double ramp_time;         /**< force ramp-in on engagement and ramp-out on stale data or a
                                   fault (s), >= 0; default 0.05 */
    double stale_after;       /**< full-model data older than this (s of haptic time) is
                                   stale: the force ramps out; >= dt; default 0.1 */
} sh_haptic_def;

/** Fill a haptic def with defaults (the tool stays 0 and must be set). Thread: any.
 *  Alloc: none. */
SH_API void sh_haptic_def_default(sh_haptic_def* def);

/** Bytes of memory a context made from def holds (its whole arena: the three exchanged
 *  buffers and the haptic side's working state), fixed at creation. Thread: any. Alloc: none. */
SH_API sh_status sh_haptic_memory_bytes(const sh_haptic_def* def, size_t* out_bytes);

/** Fault bits of sh_haptic_output.faults: why the force is held or ramping out. */
typedef enum sh_haptic_fault {
    SH_HAPTIC_FAULT_POSE = 1,     /**< the device pose was not finite (or a zero quaternion):
                                       the last good pose is kept */
    SH_HAPTIC_FAULT_DT = 2,       /**< dt was not finite, <= 0 or > 1 s: nothing was stepped */
    SH_HAPTIC_FAULT_UNSTABLE = 4, /**< the buffer went non-finite or ran away: it was rolled
                                       back to its state before the step */
    SH_HAPTIC_FAULT_STALE = 8,    /**< the full-model data is older than stale_after */
    SH_HAPTIC_FAULT_NO_TOOL = 16  /**< the tool or the world is gone */
} sh_haptic_fault;

/** What one haptic step rendered. */
typedef struct sh_haptic_output {
    double force[3];        /**< force to render on the device (N, world frame): the tissue's
                                 push on the tool, clamped to max_force and max_force_rate and
                                 ramped; always finite */
    double torque[3];       /**< torque on the tool about its position (N m, world frame),
                                 scaled like the force */
    int32_t contact;        /**< 1 if the tool touches the buffer (or the proxy surface) */
    int32_t buffer_tets;    /**< tets in the buffer in use */
    int32_t buffer_nodes;   /**< nodes in the buffer in use */
    int32_t substeps;       /**< explicit sub-steps taken to stay below the critical step */
    double data_age;        /**< haptic time (s) since the newest full-model data arrived */
    uint32_t faults;        /**< sh_haptic_fault bits raised in this step */
    uint32_t warnings;      /**< bit (1 << sh_warning) for each kind raised in this step */
    double raw_force[3];    /**< the buffer's force before clamping and ramps (N) */
} sh_haptic_output;

/** Create a haptic context on world for def.tool. The buffer is extracted at once and again
 *  at the end of every sh_world_step, around the point of the nearest FEM body's surface
 *  nearest the tool; the world then moves the tool to the latest device pose before each
 *  step, so the full model feels the tool where the device is. Thread: sim. Alloc: may (the
 *  whole arena, once). */
SH_API sh_status sh_haptic_create(sh_world* world, const sh_haptic_def* def,
                                  sh_haptic** out_haptic);

/** Destroy a context (after the haptic thread has stopped calling sh_haptic_step on it). It
 *  may outlive its world. NULL is a no-op returning SH_OK; a destroyed pointer returns
 *  SH_ERR_INVALID_HANDLE. Thread: sim. Alloc: none. */
SH_API sh_status sh_haptic_destroy(sh_haptic* haptic);

/** Step the buffer by dt to the device pose (position m, orientation unit quaternion
 *  (w, x, y, z), world frame) and fill out_output. The full model's newest buffer is taken up (its
 *  interior nodes keep the state the haptic side gave them), its boundary nodes follow the
 *  full model across the full-model step, the interior is integrated explicitly (sub-stepped
 *  below its critical step) under the tool's Hunt-Crossley contact, and the force is the
 *  buffer's push on the tool. Before the first buffer arrives the tool presses on a proxy: the
 *  plane of the last known nearest surface point. out_output is always filled and finite; bad input
 *  (a NULL pointer, a non-finite pose or dt) is a status plus a fault bit, with the force held
 *  and ramping out; a NULL or destroyed context is SH_ERR_INVALID_HANDLE (checked without a
 *  lock and without reading the context). Thread: haptic (one thread at a
 *  time per context, concurrent with the sim thread). Alloc: none. Locks: none. */
SH_API sh_status sh_haptic_step(sh_haptic* haptic, const double position[3],
                                const double orientation[4], double dt,
                                sh_haptic_output* out_output);

/** Read the context's warning counters (SH_WARN_COUNT values: SH_WARN_FORCE_CLAMPED for
 *  clamped forces and rates, SH_WARN_CAPACITY for buffers cut to capacity, SH_WARN_UNSTABLE
 *  for roll-backs). Thread: sim. Alloc: none. */
SH_API sh_status sh_haptic_get_warnings(const sh_haptic* haptic,
                                        uint64_t out_counts[SH_WARN_COUNT]);

/** @} */

/** @defgroup sh_api_device Device mapping
 *  From a haptic device's workspace to the world and back, and the rendered force to the
 *  device: the scale, base pose, tool offset and force scale a host sets up once.
 *  @{ */

/** How a device's frame and units map to the world: a device pose (p_d, q_d) is the world
 *  pose p = base_position + scale R_base (p_d + R_d tool_offset), q = q_base q_d. A device in
 *  mm with y up (OpenHaptics, CHAI3D) in a z-up world in metres: scale 0.001 and base_orientation
 *  a quarter turn about x, (cos 45 deg, sin 45 deg, 0, 0). Initialise with
 *  sh_device_mapping_default. */
typedef struct sh_device_mapping {
    uint32_t internal_init;     /**< set by sh_device_mapping_default; do not touch */
    double scale;               /**< world metres per device length unit (0.001: a device in mm;
                                     times any motion scaling), finite and > 0; default 1 */
    double base_position[3];    /**< the device frame's origin in the world (m); default 0 */
    double base_orientation[4]; /**< the device frame's orientation in the world (quaternion
                                     w, x, y, z; normalised when used, not zero); default
                                     identity */
    double tool_offset[3];      /**< the tool point in the device's end-effector frame (device
                                     units; e.g. a stylus tip); default 0 */
    double force_scale;         /**< device force per world force (N/N; below 1 softens what the
                                     hand feels), finite and > 0; default 1 */
} sh_device_mapping;

/** Fill a mapping with defaults (the identity). Thread: any. Alloc: none. */
SH_API void sh_device_mapping_default(sh_device_mapping* mapping);

/** Check a mapping once (sim side, before the device loop uses it): SH_ERR_UNINITIALIZED_DEF,
 *  or SH_ERR_INVALID_ARGUMENT with the field named in sh_last_error_message(). Thread: any.
 *  Alloc: may (the message). */
SH_API sh_status sh_device_mapping_check(const sh_device_mapping* mapping);

/** The world pose of the tool for a device pose: position in device units, orientation a
 *  quaternion (w, x, y, z) in the device frame (normalised here). SH_ERR_INVALID_ARGUMENT if
 *  a pointer is NULL, the mapping fails sh_device_mapping_check or the pose is not finite (or a
 *  zero quaternion): the outputs are then untouched. Never allocates, locks or sets the
 *  last-error message, so a device loop may call it. Thread: any. Alloc: none. */
SH_API sh_status sh_device_to_world(const sh_device_mapping* mapping, const double device_position[3],
                                    const double device_orientation[4], double out_position[3],
                                    double out_orientation[4]);

/** The inverse of sh_device_to_world: the device pose that puts the tool at a world pose.
 *  Errors and threads as sh_device_to_world. Thread: any. Alloc: none. */
SH_API sh_status sh_world_to_device(const sh_device_mapping* mapping, const double position[3],
                                    const double orientation[4], double out_device_position[3],
                                    double out_device_orientation[4]);

/** What the device renders for a world wrench on the tool (e.g. sh_haptic_output.force and
 *  torque): the force and torque turned into the device frame and multiplied by force_scale
 *  (N, N m; device lengths do not enter). Errors and threads as sh_device_to_world.
 *  Thread: any. Alloc: none. */
SH_API sh_status sh_device_force(const sh_device_mapping* mapping, const double force[3],
                                 const double torque[3], double out_device_force[3],
                                 double out_device_torque[3]);

/** @} */

#ifdef __cplusplus
}
#endif

#endif /* SOFTHAP_H */

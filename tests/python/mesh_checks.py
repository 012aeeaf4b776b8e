"""Geometry and topology checks of tetrahedral meshes and their boundary surfaces, computed in
numpy from node positions and index arrays alone (no library call), for the cutting tests:
tet volumes, lumped masses, connected pieces, surface area, the boundary of a tet set,
closedness, orientation and manifoldness of a surface, and triangles spanning a cutting
plane."""

import numpy as np

# The outward faces (counter-clockwise seen from outside) of a positively oriented tet
# (a, b, c, d), as corner positions: (a, c, b), (a, b, d), (a, d, c), (b, c, d).
TET_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


# ------------------------------------------------------------------------------------------
# volumes, masses and areas


def tet_volumes(positions, tets):
    """Signed volume of each tet, (b - a) . ((c - a) x (d - a)) / 6 (m^3)."""
    x = np.asarray(positions, dtype=float)[np.asarray(tets)]
    edges = x[:, 1:] - x[:, :1]
    return np.einsum("ij,ij->i", edges[:, 0], np.cross(edges[:, 1], edges[:, 2])) / 6.0


def lumped_masses(positions, tets, density):
    """Lumped node masses of a uniform body: each tet's mass density * V shared equally by its
    four nodes (kg)."""
    masses = np.zeros(len(positions))
    shares = np.repeat(density * tet_volumes(positions, tets) / 4.0, 4)
    np.add.at(masses, np.asarray(tets).ravel(), shares)
    return masses


def triangle_areas(positions, triangles):
    """Area of each triangle (m^2)."""
    x = np.asarray(positions, dtype=float)[np.asarray(triangles).reshape(-1, 3)]
    return 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)


def enclosed_volume(positions, triangles):
    """Volume enclosed by a closed triangulated surface by the divergence theorem, the sum of
    a . (b x c) / 6 over its triangles (a, b, c): positive when they face outward (m^3)."""
    x = np.asarray(positions, dtype=float)[np.asarray(triangles).reshape(-1, 3)]
    return float(np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6.0)


# ------------------------------------------------------------------------------------------
# connected pieces


def connected_labels(count, pairs):
    """Connected components of the graph on count vertices with edges pairs ((k, 2) ints):
    for each vertex the smallest vertex of its component (hook-and-compress union-find)."""
    label = np.arange(count)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    while True:
        li, lj = label[pairs[:, 0]], label[pairs[:, 1]]
        low = np.minimum(li, lj)
        hooked = label.copy()
        np.minimum.at(hooked, li, low)
        np.minimum.at(hooked, lj, low)
        while True:  # point every vertex at its root
            jumped = hooked[hooked]
            if np.array_equal(jumped, hooked):
                break
            hooked = jumped
        if np.array_equal(hooked, label):
            return label
        label = hooked


def components(node_count, tets):
    """Pieces of a tet mesh (tets sharing a node are one piece): (tet_label, piece_count) with
    tet_label[t] in 0 .. piece_count - 1, and node_label (n,) giving each node's piece (-1 for
    nodes in no tet)."""
    tets = np.asarray(tets, dtype=np.int64)
    pairs = np.concatenate([tets[:, [0, k]] for k in (1, 2, 3)])
    roots = connected_labels(node_count, pairs)
    used, tet_label = np.unique(roots[tets[:, 0]], return_inverse=True)
    node_label = np.full(node_count, -1)
    node_label[tets.ravel()] = np.repeat(tet_label, 4)
    return tet_label, len(used), node_label


def piece_surfaces(node_count, tets, triangles):
    """The surface triangles of each piece of the mesh (components): a list of (k, 3)
    arrays, in the order of the piece labels."""
    _, count, node_label = components(node_count, tets)
    triangles = np.asarray(triangles).reshape(-1, 3)
    owner = node_label[triangles[:, 0]]
    return [triangles[owner == k] for k in range(count)]


# ------------------------------------------------------------------------------------------
# surfaces


def canonical_rows(triangles):
    """Triangles rotated so that each row starts at its smallest index (orientation kept),
    rows sorted: two lists of oriented triangles are equal iff their canonical_rows are."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    shift = np.argmin(t, axis=1)
    rows = np.stack([t[np.arange(len(t)), (shift + k) % 3] for k in range(3)], axis=1)
    return rows[np.lexsort(rows.T[::-1])]


def boundary_faces(tets):
    """The faces of positively oriented tets that belong to one tet only, oriented outward
    (counter-clockwise seen from outside), as canonical_rows."""
    faces = np.asarray(tets, dtype=np.int64)[:, TET_FACES].reshape(-1, 3)
    keys = np.sort(faces, axis=1)
    keys = (keys[:, 0] << 42) + (keys[:, 1] << 21) + keys[:, 2]  # node indices < 2^21
    _, first, counts = np.unique(keys, return_index=True, return_counts=True)
    return canonical_rows(faces[first[counts == 1]])


def _pair_keys(a, b):
    return np.asarray(a, dtype=np.int64) * (1 << 31) + np.asarray(b, dtype=np.int64)


def edge_problems(triangles):
    """Surface defects over the edges: (number of undirected edges not in exactly two
    triangles, number of directed edges in more than one triangle (orientation not
    consistent))."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    a, b = t.ravel(), t[:, [1, 2, 0]].ravel()
    _, undirected = np.unique(_pair_keys(np.minimum(a, b), np.maximum(a, b)), return_counts=True)
    _, directed = np.unique(_pair_keys(a, b), return_counts=True)
    return int(np.count_nonzero(undirected != 2)), int(np.count_nonzero(directed != 1))


def non_manifold_vertices(triangles):
    """Vertices whose triangles do not form a single fan, sorted: a vertex's triangles, joined
    where two of them share an edge at the vertex, must be one connected group."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    corner = np.arange(t.size).reshape(-1, 3)  # corner 3 i + k: vertex t[i, k] of triangle i
    v, w = t.ravel(), t[:, [1, 2, 0]].ravel()
    cv, cw = corner.ravel(), corner[:, [1, 2, 0]].ravel()
    # each edge (v, w) of a triangle ties the triangle's corners at v and at w to those of
    # the other triangles on the edge
    edge_key = _pair_keys(np.minimum(v, w), np.maximum(v, w))
    keys = np.concatenate([edge_key, edge_key])
    vertex = np.concatenate([v, w])
    corners = np.concatenate([cv, cw])
    order = np.lexsort((vertex, keys))
    keys, vertex, corners = keys[order], vertex[order], corners[order]
    same = (keys[1:] == keys[:-1]) & (vertex[1:] == vertex[:-1])
    pairs = np.stack([corners[:-1][same], corners[1:][same]], axis=1)
    fan = connected_labels(t.size, pairs)
    fans = np.unique(np.stack([t.ravel(), fan], axis=1), axis=0)[:, 0]
    counts = np.bincount(fans)
    return np.flatnonzero(counts > 1)


def euler_characteristic(triangles):
    """V - E + F of a triangulated surface (V its vertices, E its edges, F its triangles)."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    a, b = t.ravel(), t[:, [1, 2, 0]].ravel()
    edges = np.unique(_pair_keys(np.minimum(a, b), np.maximum(a, b)))
    return len(np.unique(t)) - len(edges) + len(t)


def root_nodes(parents):
    """Each node's original node: its parent chain followed to a node with parent -1."""
    parents = np.asarray(parents)
    roots = np.arange(len(parents))
    for i in np.flatnonzero(parents >= 0):  # a parent precedes its children: one pass
        roots[i] = roots[parents[i]]
    return roots


def mesh_edges(tets):
    """The undirected edges (lo, hi) of a tet mesh, a sorted unique (k, 2) array."""
    tets = np.asarray(tets, dtype=np.int64)
    pairs = np.concatenate([tets[:, [i, j]] for i in range(4) for j in range(i + 1, 4)])
    keys = np.unique(_pair_keys(pairs.min(axis=1), pairs.max(axis=1)))
    return np.stack([keys >> 31, keys & ((1 << 31) - 1)], axis=1)


def edge_positions(positions, nodes, ends, edges):
    """For each point positions[nodes[k]], whether it lies on an edge (of the (e, 2) array
    edges) that has node ends[k] as an end, at a distance from ends[k] between 1/4 and 1/2 of
    the edge's length (1e-9 relative tolerances): a boolean array."""
    x = np.asarray(positions, dtype=float)
    nodes, ends = np.asarray(nodes, dtype=np.int64), np.asarray(ends, dtype=np.int64)
    directed = np.concatenate([edges, edges[:, ::-1]])
    directed = directed[np.argsort(directed[:, 0], kind="stable")]
    lo = np.searchsorted(directed[:, 0], ends, side="left")
    hi = np.searchsorted(directed[:, 0], ends, side="right")
    counts = hi - lo
    owner = np.repeat(np.arange(len(nodes)), counts)  # which point each candidate edge is for
    slot = np.repeat(lo - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
    p, q = directed[slot, 0], directed[slot, 1]
    d = x[q] - x[p]
    length2 = np.einsum("ij,ij->i", d, d)
    r = x[nodes[owner]] - x[p]
    s = np.einsum("ij,ij->i", r, d) / length2  # where the point projects on the edge from p
    off = np.linalg.norm(r - s[:, None] * d, axis=1)
    good = (off <= 1e-9 * np.sqrt(length2)) & (s >= 0.25 - 1e-9) & (s <= 0.5 + 1e-9)
    found = np.zeros(len(nodes), dtype=bool)
    np.logical_or.at(found, owner, good)
    return found


# ------------------------------------------------------------------------------------------
# cutting surfaces


def plane_basis(normal):
    """Unit normal n and unit vectors u, v with (u, v, n) right-handed and orthonormal."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, n)
    u /= np.linalg.norm(u)
    return n, u, np.cross(n, u)


def plane_square(point, normal, half_size, u_range=None):
    """Two triangles, a (2, 3, 3) array, covering the square [-half_size, half_size]^2 (in
    the plane_basis coordinates u, v) of the plane through point with the given normal;
    u_range = (lo, hi) narrows the u coordinate to a strip (a partial cut)."""
    _, u, v = plane_basis(normal)
    p = np.asarray(point, dtype=float)
    lo, hi = u_range if u_range is not None else (-half_size, half_size)
    a, b = p + lo * u - half_size * v, p + hi * u - half_size * v
    c, d = p + hi * u + half_size * v, p + lo * u + half_size * v
    return np.array([[a, b, c], [a, c, d]])


def rectangle(x_range, y_range, z):
    """Two triangles covering the rectangle x_range x y_range of the plane z = const."""
    (x0, x1), (y0, y1) = x_range, y_range
    a, b, c, d = [x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]
    return np.array([[a, b, c], [a, c, d]], dtype=float)


def plane_crossings(positions, edges, point, normal):
    """Where the plane through point with the given normal crosses the edges (k, 2): the
    parameter t in [0, 1] from the first node to the second, for the edges it crosses
    (their ends strictly on opposite sides, or one end on it) as an array."""
    x = np.asarray(positions, dtype=float)
    d = (x - np.asarray(point, dtype=float)) @ np.asarray(normal, dtype=float)
    d0, d1 = d[edges[:, 0]], d[edges[:, 1]]
    crossed = (d0 * d1 <= 0) & (d0 != d1)
    return d0[crossed] / (d0[crossed] - d1[crossed])

"""Generated meshes for tests and benchmarks: icosphere, midpoint subdivision, flat grids, discs (numpy/scipy)."""

import numpy as np


def subdivide(points, triangles):
    """Split every triangle into four at its edge midpoints (the surface is unchanged)."""
    from .topology import unique_edges

    unique, edge_of_corner = unique_edges(triangles)
    edge_of_corner = edge_of_corner + len(points)
    mids = 0.5 * (points[unique[:, 0]] + points[unique[:, 1]])
    a, b, c = np.asarray(triangles, dtype=np.int64).T
    ab, bc, ca = edge_of_corner.T
    tris = np.concatenate([np.stack(t, 1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return np.concatenate([points, mids]), tris


def icosphere(level, radius=1.0, centre=(0.0, 0.0, 0.0)):
    """Icosahedron subdivided ``level`` times and projected on a sphere; outward counter-clockwise triangles."""
    t = (1 + 5**0.5) / 2
    points = np.array(
        [
            [-1, t, 0],
            [1, t, 0],
            [-1, -t, 0],
            [1, -t, 0],
            [0, -1, t],
            [0, 1, t],
            [0, -1, -t],
            [0, 1, -t],
            [t, 0, -1],
            [t, 0, 1],
            [-t, 0, -1],
            [-t, 0, 1],
        ],
        float,
    )
    triangles = np.array(
        [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ]
    )
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    for _ in range(level):
        points, triangles = subdivide(points, triangles)
        points /= np.linalg.norm(points, axis=1, keepdims=True)
    return points * radius + np.asarray(centre, float), triangles.astype(np.int64)


def grid(side, spacing):
    """Square of ``side`` mm in the z = 0 plane, centred at the origin, normal +z, two triangles per cell."""
    k = int(round(side / spacing))
    xs = np.linspace(-side / 2, side / 2, k + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    points = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)
    idx = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return points, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int64)


def disc(radius, rings):
    """Flat disc in the z = 0 plane (normal +z): concentric rings of points, Delaunay-triangulated."""
    from scipy.spatial import Delaunay

    xy = [np.zeros((1, 2))]
    for k in range(1, rings + 1):
        angles = np.arange(6 * k) * 2 * np.pi / (6 * k)
        xy.append(np.stack([np.cos(angles), np.sin(angles)], 1) * radius * k / rings)
    xy = np.concatenate(xy)
    triangles = Delaunay(xy).simplices.astype(np.int64)
    e1 = xy[triangles[:, 1]] - xy[triangles[:, 0]]
    e2 = xy[triangles[:, 2]] - xy[triangles[:, 0]]
    flip = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    triangles[flip] = triangles[flip][:, ::-1]
    return np.concatenate([xy, np.zeros((len(xy), 1))], axis=1), triangles


def box(half_sizes, centre=(0.0, 0.0, 0.0)):
    """Closed box of half side lengths ``(a, b, c)`` in mm: 8 corners, 12 outward counter-clockwise triangles."""
    a, b, c = (float(h) for h in half_sizes)
    signs = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], float)
    points = signs * [a, b, c] + np.asarray(centre, float)
    # corner index = x + 2 y + 4 z with 0 for the minus side; each face as two triangles seen from outside
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = [t for p, q, r, s in faces for t in ((p, q, r), (p, r, s))]
    return points, np.array(triangles, dtype=np.int64)


def torus(major_radius, minor_radius, n_major=48, n_minor=24):
    """Closed torus about the z axis in mm (a concave, closed test surface); outward counter-clockwise triangles."""
    u = np.linspace(0.0, 2.0 * np.pi, n_major, endpoint=False)
    v = np.linspace(0.0, 2.0 * np.pi, n_minor, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    ring = major_radius + minor_radius * np.cos(vv)
    points = np.stack([ring * np.cos(uu), ring * np.sin(uu), minor_radius * np.sin(vv)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    a = i * n_minor + j
    b = ((i + 1) % n_major) * n_minor + j
    c = ((i + 1) % n_major) * n_minor + (j + 1) % n_minor
    d = i * n_minor + (j + 1) % n_minor
    triangles = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return points, triangles.astype(np.int64)

"""Shadow rays: Embree (embreex) occlusion queries against one triangle mesh.

An :class:`Occluder` builds one Embree scene per mesh (float32, C-contiguous, committed once) and
answers "is the way from these surface points toward the light free?" for rays to infinity
(directional lights, environment samples) and for segments (point lights); :meth:`Occluder.intersect`
also says which triangle a ray meets first, and where (the bounce gather,
:mod:`translucency.scatter.bounces`). Rays start at the surface point moved along its normal by a
scale-aware offset ``epsilon``; without it nearly every ray hits one of the faces around its own
vertex (float32 rounding puts the origin on either side of them). Large ray sets run in chunks on a
thread pool: embreex releases the GIL while it traces.

Choice of the offset (vertices with ``n . w > 0``): an offset well above float32 rounding removes every
self-hit caused by rounding (no ray hits a face of its own one-ring that faces the light). What remains
are hits on one-ring faces that face *away* from the light: vertices at the shadow terminator or in a
crease, which the surrounding geometry really does block; they carry a small share of the
cosine-weighted flux, more on raw photogrammetry than on clean scans. The default
``RELATIVE_OFFSET = 1e-4`` of the bounding-box diagonal (0.025 mm for a 250 mm diagonal, a small
fraction of a scan's mean edge) is far above rounding, removes part of those terminator hits, and is
too small to leak light through any feature a scan resolves. It is floored at 64 float32 ulps of
the largest coordinate, so a mesh far from the origin still gets a working offset.

A :class:`VisibilityCache` keeps Embree scenes (per mesh) and every light sample's visibility (per
mesh, ray origins and light geometry) across calls, so a material change traces no ray again.

========== ========================================================== ======
symbol     meaning                                                    unit
========== ========================================================== ======
points     mesh vertices                                              mm
triangles  vertex indices of the triangles                            1
epsilon    offset of ray origins along the normal                     mm
origins    surface points the rays leave from (before the offset)     mm
w          unit ray direction (toward the light)                      1
distance   segment length to a point light (None: to infinity)        mm
========== ========================================================== ======
"""

from __future__ import annotations

import hashlib
import weakref
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import numpy as np

from ..errors import InvalidParameterError, MeshError, TranslucencyError
from ..processes import available_cores

__all__ = ["Hits", "Occluder", "VisibilityCache", "RELATIVE_OFFSET", "array_digest"]

RELATIVE_OFFSET = 1e-4
"""Default ray-origin offset as a fraction of the mesh's bounding-box diagonal (module docstring)."""

ULP_FLOOR = 64.0 * float(np.finfo(np.float32).eps)
"""The offset is at least this fraction of the largest absolute coordinate (64 float32 ulps)."""

MIN_RAYS_PER_CHUNK = 16384
"""Below this many rays per worker the rays run on the calling thread (pool overhead dominates)."""

INFINITE_DISTANCE = 1e37  # embreex's "no limit" tfar, representable in float32


class Hits(NamedTuple):
    """Where rays first meet the mesh (:meth:`Occluder.intersect`).

    Attributes
    ----------
    triangle : ndarray of int64, shape (k,)
        Index of the triangle hit, -1 where the ray escapes.
    u, v : ndarray, shape (k,)
        Barycentrics of the hit point, ``(1 - u - v) p0 + u p1 + v p2`` (0 where it escapes), 1.
    distance : ndarray, shape (k,)
        From the offset origin to the hit, mm (inf where it escapes).
    """

    triangle: np.ndarray
    u: np.ndarray
    v: np.ndarray
    distance: np.ndarray


def _embreex():
    try:
        from embreex import mesh_construction, rtcore_scene
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise TranslucencyError(
            f"shadow rays need the embreex package (Embree ray tracing), which failed to import ({exc}); "
            "install it with 'pip install embreex' or turn visibility off."
        ) from None
    return rtcore_scene, mesh_construction


def array_digest(*arrays) -> str:
    """Hex digest of the dtype, shape and bytes of arrays (cache keys of meshes and ray origins).

    An array that owns its memory and is read-only (a :class:`~translucency.geometry.mesh.TriangleMesh`'s points
    and triangles, the Scene's normals) is hashed once while it lives: a relit light looks its mesh up again and
    again, and hashing the bunny's arrays took about 2 ms a light."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        h.update(_digest_of(a))
    return h.hexdigest()


#: Digests of read-only arrays that own their memory, by ``id``, with a weak reference that drops the entry when
#: the array is freed (so that a new array at the same address is not taken for it).
_KNOWN_DIGESTS: dict[int, tuple] = {}


def _digest_of(a) -> bytes:
    """The digest of one array's dtype, shape and bytes (remembered for read-only arrays, :func:`array_digest`)."""
    frozen = isinstance(a, np.ndarray) and not a.flags.writeable and a.flags.owndata
    if frozen:
        known = _KNOWN_DIGESTS.get(id(a))
        if known is not None and known[0]() is a:
            return known[1]
    c = np.ascontiguousarray(a)
    h = hashlib.blake2b(f"{c.dtype.str}{c.shape}".encode(), digest_size=16)
    h.update(c.view(np.uint8).reshape(-1).data if c.size else b"")
    digest = h.digest()
    if frozen:
        key = id(a)
        _KNOWN_DIGESTS[key] = (weakref.ref(a, lambda _, key=key: _KNOWN_DIGESTS.pop(key, None)), digest)
    return digest


class Occluder:
    """One Embree scene of a triangle mesh, for shadow rays.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions, mm (converted to float32, C-contiguous, for Embree).
    triangles : array_like, shape (m, 3)
        Vertex indices of the triangles.
    relative_offset : float, optional
        Ray-origin offset along the normal as a fraction of the bounding-box diagonal (default
        :data:`RELATIVE_OFFSET`; floored at 64 float32 ulps of the largest coordinate).
    workers : int, optional
        Threads for large ray sets (default: the CPU cores this process may use).

    Attributes
    ----------
    epsilon : float
        The offset in mm.
    key : str
        Digest of the points, triangles and offset (identifies the scene in caches).
    rays_cast : int
        Rays traced since construction.
    """

    def __init__(self, points, triangles, *, relative_offset: float = RELATIVE_OFFSET, workers: int | None = None):
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
            raise MeshError(f"occluder: points must have shape (n, 3) with n > 0, got {points.shape}.")
        if not np.all(np.isfinite(points)):
            raise MeshError("occluder: points contain NaN or infinite coordinates; clean the mesh first.")
        try:
            triangles = np.asarray(triangles)
        except (TypeError, ValueError):
            raise MeshError("occluder: triangles must be an (m, 3) integer array.") from None
        if triangles.size == 0:
            triangles = triangles.reshape(0, 3)
        if triangles.ndim != 2 or triangles.shape[1] != 3 or not np.issubdtype(triangles.dtype, np.integer):
            raise MeshError(
                f"occluder: triangles must be an (m, 3) integer array, got {triangles.dtype} {triangles.shape}."
            )
        if len(triangles) and (triangles.min() < 0 or triangles.max() >= len(points)):
            raise MeshError(
                f"occluder: triangle indices must lie in [0, {len(points) - 1}], got "
                f"[{triangles.min()}, {triangles.max()}]."
            )
        if not (np.isfinite(relative_offset) and relative_offset > 0):
            raise InvalidParameterError(
                f"occluder: relative_offset must be a positive number, got {relative_offset!r}."
            )
        self.workers = available_cores() if workers is None else int(workers)
        if self.workers < 1:
            raise InvalidParameterError(f"occluder: workers must be >= 1, got {workers!r}.")
        used = np.zeros(len(points), dtype=bool)
        used[triangles.reshape(-1)] = True
        used = points[used] if len(triangles) else points
        diagonal = float(np.linalg.norm(used.max(axis=0) - used.min(axis=0)))
        self.epsilon = max(relative_offset * diagonal, ULP_FLOOR * float(np.abs(used).max()), np.finfo(np.float32).tiny)
        self.key = array_digest(points, triangles.astype(np.int64), np.array([relative_offset]))
        self.n_triangles = len(triangles)
        self.rays_cast = 0
        self._scene = None
        if self.n_triangles:
            rtcore_scene, mesh_construction = _embreex()
            self._scene = rtcore_scene.EmbreeScene()
            self._mesh = mesh_construction.TriangleMesh(
                self._scene,
                np.ascontiguousarray(points, dtype=np.float32),
                np.ascontiguousarray(triangles, dtype=np.int32),
            )
            # The first query commits the scene; do it here, single-threaded, before any pool uses it.
            self._scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), query="OCCLUDED")

    def visible(self, origins, normals, directions, distances=None) -> np.ndarray:
        """Whether each ray from a surface point toward its light is unobstructed.

        Every ray given is traced; skip back-facing points (``n . w <= 0``) before calling.

        Parameters
        ----------
        origins : array_like, shape (k, 3)
            Surface points, mm; each ray starts at ``origin + epsilon * normal``.
        normals : array_like, shape (k, 3)
            Unit outward normals at the origins.
        directions : array_like, shape (3,) or (k, 3)
            Unit directions toward the light (one for all rays, or one per ray).
        distances : array_like, shape (k,), optional
            Distance from each origin to a point light, mm; a ray is blocked only by geometry closer
            than that. None, or ``inf`` for single rays: to infinity.

        Returns
        -------
        ndarray of bool, shape (k,)
            True where nothing of the mesh lies between the (offset) origin and the light.
        """
        origins = np.asarray(origins, dtype=np.float64)
        k = len(origins)
        if k == 0 or self._scene is None:
            return np.ones(k, dtype=bool)
        directions = np.broadcast_to(np.asarray(directions, dtype=np.float64), (k, 3))
        start = origins + self.epsilon * np.asarray(normals, dtype=np.float64)
        ray_origins = np.ascontiguousarray(start, dtype=np.float32)
        ray_directions = np.ascontiguousarray(directions, dtype=np.float32)
        tfar = np.full(k, INFINITE_DISTANCE, dtype=np.float32)
        if distances is not None:
            distances = np.asarray(distances, dtype=np.float64)
            segment = np.flatnonzero(np.isfinite(distances))
            # Measured from the offset origin, and stopped just short of the light itself.
            target = origins[segment] + directions[segment] * distances[segment, None]
            tfar[segment] = np.linalg.norm(target - start[segment], axis=1) * (1.0 - 1e-6)
        hit = self._run(ray_origins, ray_directions, tfar)
        self.rays_cast += k
        return hit < 0

    def first_hits(self, origins, directions, max_distance=None) -> Hits:
        """The first triangle each ray meets, and where, for rays from the points given as they are.

        Unlike :meth:`visible` and :meth:`intersect` the origins are not moved: a caller starting on the
        surface offsets them itself (the path tracer moves along the ray, not the normal).

        Parameters
        ----------
        origins, directions : array_like, shape (k, 3)
            Ray origins (mm) and unit directions.
        max_distance : array_like, shape (k,), optional
            Only hits nearer than this count, mm (default: to infinity).

        Returns
        -------
        Hits
            Per ray: the triangle hit (-1 where the ray escapes), the barycentrics ``u, v`` of the hit
            point (``(1 - u - v) p0 + u p1 + v p2`` over the triangle's vertices) and its distance (mm).
        """
        origins = np.ascontiguousarray(origins, dtype=np.float32)
        k = len(origins)
        if k == 0 or self._scene is None:
            return Hits(np.full(k, -1, np.int64), np.zeros(k), np.zeros(k), np.full(k, np.inf))
        directions = np.ascontiguousarray(np.broadcast_to(directions, (k, 3)), dtype=np.float32)
        tfar = np.full(k, INFINITE_DISTANCE, dtype=np.float32)
        if max_distance is not None:
            tfar = np.ascontiguousarray(np.minimum(max_distance, INFINITE_DISTANCE), dtype=np.float32)
        out = self._run(origins, directions, tfar, query="INTERSECT", output=True)
        self.rays_cast += k
        triangle = out["primID"].astype(np.int64)
        missed = triangle < 0
        u = np.where(missed, 0.0, out["u"].astype(np.float64))
        v = np.where(missed, 0.0, out["v"].astype(np.float64))
        distance = np.where(missed, np.inf, out["tfar"].astype(np.float64))
        return Hits(triangle, u, v, distance)

    def intersect(self, origins, normals, directions) -> Hits:
        """:meth:`first_hits` of rays from surface points moved ``epsilon`` along their normals (as in
        :meth:`visible`; the bounce gather's rays)."""
        start = np.asarray(origins, dtype=np.float64) + self.epsilon * np.asarray(normals, dtype=np.float64)
        return self.first_hits(start, directions)

    def _run(self, origins, directions, tfar, query="OCCLUDED", output=False):
        k = len(origins)
        n_chunks = min(self.workers * 4, k // MIN_RAYS_PER_CHUNK)

        def trace(s):
            return self._scene.run(origins[s], directions[s], dists=tfar[s].copy(), query=query, output=output)

        if self.workers == 1 or n_chunks < 2:
            return trace(slice(0, k))
        bounds = np.linspace(0, k, n_chunks + 1).astype(np.int64)
        chunks = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
        with ThreadPoolExecutor(max_workers=self.workers) as pool:
            parts = list(pool.map(trace, chunks))
        if output:
            return {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}
        return np.concatenate(parts)


class VisibilityCache:
    """Memo of Embree scenes (per mesh) and visibility (per mesh, ray origins and light geometry).

    Keep one across solves of the same mesh and lights: changing only the material (coefficients,
    ``eta``) then traces no ray and builds no scene. Entries are dropped least recently used first.

    Parameters
    ----------
    max_entries : int, optional
        Most visibility arrays kept (one per light sample and mesh).
    max_scenes : int, optional
        Most Embree scenes kept.
    """

    def __init__(self, max_entries: int = 4096, max_scenes: int = 4):
        self.max_entries = int(max_entries)
        self.max_scenes = int(max_scenes)
        self._scenes: OrderedDict[str, Occluder] = OrderedDict()
        self._visibility: OrderedDict[tuple, np.ndarray] = OrderedDict()
        self.hits = 0
        self.misses = 0

    def occluder(self, points, triangles, **options) -> tuple[Occluder, bool]:
        """The :class:`Occluder` of a mesh, and whether it was reused (True) or built now."""
        key = array_digest(np.asarray(points, dtype=np.float64), np.asarray(triangles, dtype=np.int64)) + repr(
            sorted(options.items())
        )
        if key in self._scenes:
            self._scenes.move_to_end(key)
            return self._scenes[key], True
        occluder = Occluder(points, triangles, **options)
        self._scenes[key] = occluder
        while len(self._scenes) > self.max_scenes:
            self._scenes.popitem(last=False)
        return occluder, False

    def clear(self) -> None:
        """Drop every scene and visibility array (their memory is freed once nothing else holds them)."""
        self._scenes.clear()
        self._visibility.clear()

    def release_scenes(self) -> None:
        """Drop the Embree scenes (built again on their next use) and keep the visibility arrays."""
        self._scenes.clear()

    def get(self, key: tuple):
        """Stored visibility for ``key``, or None."""
        value = self._visibility.get(key)
        if value is None:
            self.misses += 1
            return None
        self.hits += 1
        self._visibility.move_to_end(key)
        return value

    def put(self, key: tuple, value: np.ndarray) -> None:
        """Store a visibility array (read-only) under ``key``."""
        value = np.asarray(value, dtype=bool)
        value.setflags(write=False)
        self._visibility[key] = value
        while len(self._visibility) > self.max_entries:
            self._visibility.popitem(last=False)

    def __len__(self) -> int:
        return len(self._visibility)

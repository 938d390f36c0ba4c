"""Decimation to the solver's resolution (the proxy) and the mapping of proxy values back to the full mesh.

The scattering solver needs vertices only as dense as the diffusion length asks; a scan usually
has many more. :func:`decimate_mesh` builds a coarser *proxy* of the same shape, and a
:class:`ProxyMapping` that carries per-vertex values computed on the proxy back to every vertex of
the full mesh.

Methods
    ``"fast-simplification"`` (default): the quadric edge-collapse of the ``fast-simplification``
    package (Sven Forstmann's Fast-Quadric-Mesh-Simplification), much faster than pymeshlab's.
    It runs on one core, so a mesh of millions of triangles is cut into
    slabs decimated side by side in child processes, each with its cut kept, then welded and decimated
    once more over the whole (:func:`decimation_parts`; time, memory and the proxy's quality:
    bench/README.md, "Decimation in parts"). ``"pymeshlab"``: pymeshlab's quadric edge collapse
    (``meshing_decimation_quadric_edge_collapse``) with normal and topology preservation, slower
    and more careful.

Target
    a number of triangles, or a mean edge length ``L`` in mm: an equilateral triangle of side ``L``
    has area ``sqrt(3) / 4 L²``, so the target count is the surface area divided by that.

Mapping back
    every full-mesh vertex is projected on the proxy surface (exact closest point, see
    :mod:`translucency.geometry.proximity`) and keeps the proxy triangle and the barycentric weights of
    its projection; a value is interpolated as ``sum_i w_i value[proxy vertex i]``. The
    interpolation is continuous across proxy edges, linear inside proxy triangles, and exact where a
    full vertex coincides with a proxy vertex (weights one-hot).

================== =================================================== =====
name               meaning                                             unit
================== =================================================== =====
target_edge_length mean edge length asked for the proxy                mm
distance           distance of a full vertex to the proxy surface      mm
================== =================================================== =====
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..errors import InvalidParameterError, MeshError
from ..geometry.measure import triangle_areas
from ..geometry.mesh import TriangleMesh, validate_mesh_arrays
from ..geometry.proximity import closest_points_on_triangles
from ..geometry.topology import first_at_same_position
from .polydata import as_triangle_mesh

__all__ = [
    "METHODS",
    "ProxyMapping",
    "Decimation",
    "target_face_count",
    "simplify_arrays",
    "map_to_proxy",
    "decimate_mesh",
]

#: Decimation methods: name -> description.
METHODS = {
    "fast-simplification": "quadric edge collapse of the fast-simplification package (default, fast)",
    "pymeshlab": "pymeshlab quadric edge collapse with normal and topology preservation (slower)",
}

_MIN_FACES = 20


def target_face_count(surface_area: float, edge_length: float) -> int:
    """Number of equilateral triangles of side ``edge_length`` that cover ``surface_area``.

    Parameters
    ----------
    surface_area : float
        Area to cover, in mm².
    edge_length : float
        Side of the triangles, in mm (> 0).

    Returns
    -------
    int
        ``round(surface_area / (sqrt(3) / 4 * edge_length²))``, at least 1.
    """
    edge_length = float(edge_length)
    if not (math.isfinite(edge_length) and edge_length > 0):
        raise InvalidParameterError(f"target_edge_length is {edge_length!r}; pass a positive length in mm.")
    return max(1, int(round(surface_area / (math.sqrt(3.0) / 4.0 * edge_length**2))))


def simplify_arrays(
    points,
    triangles,
    target_faces: int,
    *,
    method: str = "fast-simplification",
    aggressiveness: float = 7.0,
    memory_limit_bytes: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Decimate triangle arrays to about ``target_faces`` triangles (array-level form of :func:`decimate_mesh`).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
    target_faces : int
        Triangles wanted (the result can be a little off).
    method : {"fast-simplification", "pymeshlab"}
    aggressiveness : float, default 7
        fast-simplification's ``agg`` (lower keeps the shape better and takes longer).
    memory_limit_bytes : float, optional
        What this process and its decimating children may hold together, bytes: the parts are made smaller and go
        fewer at a time so that the children fit beside what the process holds (:func:`decimation_plan`).

    Returns
    -------
    points : ndarray, shape (k, 3), float64
        Proxy vertices in mm (unreferenced vertices dropped).
    triangles : ndarray, shape (l, 3), int64

    Notes
    -----
    fast-simplification keeps its mesh in module-level state: do not call it from several threads
    at once (processes are fine). A large mesh is decimated in parts side by side first
    (:func:`decimation_parts`).
    """
    points, triangles = validate_mesh_arrays(points, triangles)
    if method not in METHODS:
        raise InvalidParameterError(f"unknown decimation method {method!r}; use one of {', '.join(METHODS)}.")
    target_faces = int(target_faces)
    if target_faces >= len(triangles):
        return _drop_unreferenced(points, triangles)
    if method == "fast-simplification":
        from ..processes import run_in_child

        try:
            parts, at_once = decimation_plan(len(triangles), memory_limit_bytes)
            welded = (
                _simplify_parts(points, triangles, target_faces, float(aggressiveness), parts, at_once)
                if parts > 1
                else None
            )
            if welded is not None:
                points, triangles = welded
            if target_faces >= len(triangles):  # the parts left no more than asked (the mesh had more: see above)
                new_points, new_triangles = points, triangles
            else:
                arguments = (
                    np.array(points, dtype=np.float64, order="C"),  # writable copies: the binding needs them
                    np.array(triangles, dtype=np.int32, order="C"),
                    target_faces,
                    float(aggressiveness),
                )
                if len(triangles) >= ISOLATED_TRIANGLES:  # its memory goes back when the child ends
                    new_points, new_triangles = run_in_child(fast_simplify, *arguments)
                else:
                    new_points, new_triangles = fast_simplify(*arguments)
        except (ValueError, RuntimeError) as exc:
            raise MeshError(f"fast-simplification failed on the mesh ({exc}); try method='pymeshlab'.") from exc
        except ChildProcessError as exc:
            raise MeshError(
                "the decimation's process ended before it answered (out of memory?); close other programs or "
                "lower the mesh's vertex count first."
            ) from exc
    else:
        from .meshlab import import_pymeshlab

        pymeshlab = import_pymeshlab()
        mesh_set = pymeshlab.MeshSet()
        mesh_set.add_mesh(
            pymeshlab.Mesh(
                vertex_matrix=np.array(points, order="C"), face_matrix=np.array(triangles, dtype=np.int32, order="C")
            )
        )
        try:
            mesh_set.meshing_decimation_quadric_edge_collapse(
                targetfacenum=target_faces,
                qualitythr=0.3,
                preservenormal=True,
                preservetopology=True,
                optimalplacement=True,
                planarquadric=True,
                autoclean=True,
            )
        except pymeshlab.PyMeshLabException as exc:
            raise MeshError(
                f"pymeshlab could not decimate the mesh ({exc}); try method='fast-simplification'."
            ) from exc
        mesh = mesh_set.current_mesh()
        mesh.compact()
        new_points, new_triangles = mesh.vertex_matrix(), mesh.face_matrix()
    new_points = np.asarray(new_points, dtype=np.float64).reshape(-1, 3)
    new_triangles = np.asarray(new_triangles, dtype=np.int64).reshape(-1, 3)
    keep = (
        (new_triangles[:, 0] != new_triangles[:, 1])
        & (new_triangles[:, 1] != new_triangles[:, 2])
        & (new_triangles[:, 0] != new_triangles[:, 2])
    )
    new_triangles = new_triangles[keep]
    if len(new_triangles) == 0:
        raise MeshError(f"decimation to {target_faces} triangles left no triangle; ask for more triangles.")
    return _drop_unreferenced(new_points, new_triangles)


#: fast-simplification keeps its mesh in module-level state after it returns (memory in proportion to the
#: input's triangles); from this many triangles on it runs in a child process
#: (:func:`translucency.processes.run_in_child`), whose memory goes back when it ends, at the cost of starting
#: one (a fixed cost, which a smaller mesh's memory does not repay).
ISOLATED_TRIANGLES = 1_000_000


#: A mesh is decimated in parts side by side, one per core, when each part has at least this many triangles
#: (:func:`decimation_parts`).
PART_TRIANGLES = 2_000_000
#: A part has at most this many triangles: fast-simplification's child holds memory in proportion to its part's
#: triangles at its peak, and a larger mesh is cut into more parts than cores, decimated as many at a time as
#: there are cores (bench/README.md, "Decimation in parts").
PART_MAX_TRIANGLES = 5_000_000
#: Each part is decimated to this multiple of its share of the target; the last pass over the welded
#: mesh takes the surplus away, with the fine strips along the cuts.
PART_SURPLUS = 1.1


def decimation_parts(n_triangles: int) -> int:
    """Parts a mesh of ``n_triangles`` is decimated in: one per thread this process may use (numba's setting:
    a batch bake's worker has its share of the cores), each of at least
    :data:`PART_TRIANGLES` triangles, and more where a part would be over :data:`PART_MAX_TRIANGLES` (1: the
    whole mesh in one pass). The proxy of a mesh decimated in parts depends on their number, so it can differ a
    little between machines with different numbers of cores (the same shape, to the decimation's accuracy)."""
    from ..threads import thread_count

    n_triangles = int(n_triangles)
    side_by_side = min(thread_count(), n_triangles // PART_TRIANGLES)
    return max(1, side_by_side, -(-n_triangles // PART_MAX_TRIANGLES))


#: Bytes a decimating child holds per triangle of its part at its peak (its copy of the part and
#: fast-simplification's own structures), calibrated on the decimation benchmark (bench/README.md, "Decimation in
#: parts"): what a memory limit is spent on when parts are sized to it.
CHILD_BYTES_PER_TRIANGLE = 350
#: Under a memory limit a part has at least this many triangles (smaller parts weld into more cut strips).
MIN_LIMITED_PART_TRIANGLES = 100_000


def decimation_plan(n_triangles: int, memory_limit_bytes: float | None = None) -> tuple[int, int]:
    """``(parts, at_once)``: the parts of :func:`decimation_parts`, and how many are decimated side by side (one per
    thread). Under ``memory_limit_bytes`` (what this process and its children may hold, bytes), the room left beside
    what the process holds now is shared: parts of at most ``room / CHILD_BYTES_PER_TRIANGLE`` triangles (at least
    :data:`MIN_LIMITED_PART_TRIANGLES`), as many at once as fit."""
    from ..memory import resident_memory
    from ..threads import thread_count

    parts, at_once = decimation_parts(n_triangles), thread_count()
    if memory_limit_bytes is None:
        return parts, at_once
    room = max(float(memory_limit_bytes) - resident_memory(), 0.0)
    largest = max(MIN_LIMITED_PART_TRIANGLES, int(room / CHILD_BYTES_PER_TRIANGLE))
    if n_triangles > largest:
        parts = max(parts, -(-int(n_triangles) // largest))
    part_bytes = -(-int(n_triangles) // parts) * CHILD_BYTES_PER_TRIANGLE
    return parts, max(1, min(at_once, int(room // part_bytes)))


def fast_simplify(points, triangles, target_faces: int, aggressiveness: float, keep_border: bool = False):
    """fast-simplification's quadric decimation of writable C-ordered arrays (float64 points in mm, int32
    triangles) to about ``target_faces`` triangles: ``(points, triangles)`` as it returns them.

    ``keep_border``: no edge with a vertex on an open border is collapsed, so those vertices keep their
    positions bit for bit (a part of a mesh keeps its cut).
    """
    import fast_simplification

    return fast_simplification.simplify(
        points, triangles, target_count=target_faces, agg=aggressiveness, preserve_border=keep_border
    )


def _simplify_parts(points, triangles, target_faces: int, aggressiveness: float, parts: int, at_once: int):
    """The mesh cut into ``parts`` slabs of triangles along its longest side, each decimated in a child process
    of its own with its cuts kept (:func:`fast_simplify` with ``keep_border``), ``at_once`` at a time, and
    welded again.

    Each part is asked for its share of ``PART_SURPLUS * target_faces`` triangles and two per vertex on its cut
    (the triangles along a kept cut stay: a part asked for fewer would be decimated far past its shape).
    Returns the welded ``(points, triangles)``; along the cuts it keeps the full mesh's vertices, which the
    caller's pass over the whole mesh decimates. None when the parts cannot be welded (:func:`_weld`): the
    caller decimates the whole mesh in one pass.
    """
    from ..processes import run_in_children

    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles)
    axis = int(np.argmax(np.ptp(points, axis=0)))
    height = points[triangles[:, 0], axis] + points[triangles[:, 1], axis] + points[triangles[:, 2], axis]
    ranks = [len(height) * k // parts for k in range(1, parts)]
    cuts = np.partition(height, ranks)[ranks]
    part_of = np.searchsorted(cuts, height, side="right")
    del height
    chosen = [triangles[part_of == part] for part in range(parts)]
    chosen = [part for part in chosen if len(part)]  # a slab of ties only: none
    del part_of
    parts = len(chosen)
    used = np.zeros((parts, len(points)), dtype=bool)
    for part in range(parts):
        used[part, chosen[part].ravel()] = True
    uses = used.sum(axis=0)
    on_cut = uses > 1
    jobs = []
    for part in range(parts):
        new_index = np.cumsum(used[part], dtype=np.int64) - 1
        share = PART_SURPLUS * target_faces * len(chosen[part]) / len(triangles)
        kept = 2 * int(np.count_nonzero(on_cut & used[part]))  # about the triangles along the kept cut
        jobs.append(
            (
                np.array(points[used[part]], dtype=np.float64, order="C"),
                np.array(new_index[chosen[part]], dtype=np.int32, order="C"),
                min(len(chosen[part]), int(share) + kept),
                aggressiveness,
                True,
            )
        )
    del chosen, used
    cut_points, cut_uses = points[on_cut], uses[on_cut]
    results = run_in_children(fast_simplify, jobs, at_once=at_once)
    del jobs
    return _weld(cut_points, cut_uses, results)


def _weld(cut_points: np.ndarray, cut_uses: np.ndarray, parts):
    """One mesh from decimated parts that share the vertices at ``cut_points`` (mm, kept bit for bit by each
    of the ``cut_uses`` parts that hold one): a part's vertex at one of those positions becomes that one vertex,
    every other vertex stays its part's own. None when some position holds more vertices of the parts than
    parts shared it (the mesh had several vertices there, and which belong together is not known)."""
    n_cut = len(cut_points)
    stacked = np.concatenate([cut_points] + [np.asarray(part_points, dtype=np.float64) for part_points, _ in parts])
    first = first_at_same_position(stacked)
    if np.any(first[:n_cut] != np.arange(n_cut)):  # two cut vertices at one position
        return None
    first = first[n_cut:]
    own = first >= n_cut
    if np.any(np.bincount(first[~own], minlength=n_cut) > cut_uses):
        return None
    index = np.where(own, n_cut + np.cumsum(own) - 1, first)
    welded_points = np.concatenate([cut_points, stacked[n_cut:][own]])
    offsets = np.cumsum([0] + [len(part_points) for part_points, _ in parts])
    welded_triangles = np.concatenate(
        [
            index[offset + np.asarray(part_triangles, dtype=np.int64)]
            for offset, (_, part_triangles) in zip(offsets, parts)
        ]
    )
    return _drop_unreferenced(welded_points, welded_triangles)


def _drop_unreferenced(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    used = np.zeros(len(points), dtype=bool)
    used[triangles.ravel()] = True
    if used.all():
        return points, triangles
    new_index = np.cumsum(used) - 1
    return points[used], new_index[triangles]


@dataclasses.dataclass(frozen=True, eq=False)
class ProxyMapping:
    """For each full-mesh vertex, the proxy triangle and barycentric weights of its closest proxy point.

    Attributes
    ----------
    triangle_index : ndarray, shape (n_full,), int64
        Proxy triangle holding the closest point.
    vertex_index : ndarray, shape (n_full, 3), int64
        The three proxy vertices of that triangle.
    weights : ndarray, shape (n_full, 3), float64
        Barycentric weights (>= 0, summing to 1).
    distance : ndarray, shape (n_full,), float64
        Distance from the full vertex to the proxy surface, in mm.
    n_proxy_points : int
        Number of proxy vertices (the length ``interpolate`` expects).
    """

    triangle_index: np.ndarray
    vertex_index: np.ndarray
    weights: np.ndarray
    distance: np.ndarray
    n_proxy_points: int

    def interpolate(self, values_on_proxy) -> np.ndarray:
        """Carry per-vertex values from the proxy to the full mesh.

        Parameters
        ----------
        values_on_proxy : array_like, shape (n_proxy, ...)
            One value (scalar, RGB triple, ...) per proxy vertex, any unit.

        Returns
        -------
        ndarray, shape (n_full, ...)
            ``sum_i weights[:, i] * values[vertex_index[:, i]]`` (float64, or the input's float
            type if it is floating point), in the unit of the input.
        """
        values = np.asarray(values_on_proxy)
        if values.ndim == 0 or values.shape[0] != self.n_proxy_points:
            raise InvalidParameterError(
                f"interpolate needs one value per proxy vertex ({self.n_proxy_points} rows), not an array of shape "
                f"{values.shape}; pass the values computed on the proxy."
            )
        if values.dtype.kind not in "fc":
            values = values.astype(np.float64)
        weights = self.weights.astype(values.dtype, copy=False).reshape(self.weights.shape + (1,) * (values.ndim - 1))
        # an explicit sum (not einsum/BLAS) so that one-hot weights reproduce values bit for bit, one corner at a
        # time so that no (n_full, 3, ...) gather is held (three times the size of the result)
        out = values[self.vertex_index[:, 0]] * weights[:, 0]
        for corner in (1, 2):
            out += values[self.vertex_index[:, corner]] * weights[:, corner]
        return out

    def gather(self, values_on_full) -> np.ndarray:
        """Carry per-vertex amounts from the full mesh onto the proxy, their sum kept: the adjoint of
        :meth:`interpolate`.

        Parameters
        ----------
        values_on_full : array_like, shape (n_full,) or (n_full, k)
            One amount (a flux, an area, ...) per full-mesh vertex, any unit.

        Returns
        -------
        ndarray, shape (n_proxy,) or (n_proxy, k), float64
            ``sum_i weights[i, c] * values[i]`` over the full vertices ``i`` mapped onto each proxy vertex (as
            corner ``c`` of their proxy triangle), in the unit of the input. Each full vertex shares its amount
            among the corners of its proxy triangle with weights summing to 1, so the column sums are kept
            and no amount moves farther than a proxy edge.
        """
        values = np.asarray(values_on_full, dtype=np.float64)
        if values.ndim not in (1, 2) or values.shape[0] != len(self.weights):
            raise InvalidParameterError(
                f"gather needs one value or row per full-mesh vertex ({len(self.weights)} rows), not an array of "
                f"shape {values.shape}; pass the values computed on the full mesh."
            )
        columns = values.reshape(len(values), -1)
        out = np.zeros((self.n_proxy_points, columns.shape[1]))
        for corner in range(3):
            for k in range(columns.shape[1]):
                out[:, k] += np.bincount(
                    self.vertex_index[:, corner],
                    weights=self.weights[:, corner] * columns[:, k],
                    minlength=self.n_proxy_points,
                )
        return out.reshape((self.n_proxy_points,) + values.shape[1:])


def map_to_proxy(full_points, proxy_points, proxy_triangles) -> ProxyMapping:
    """Map full-mesh vertices onto the proxy surface (closest point, barycentric weights).

    Parameters
    ----------
    full_points : array_like, shape (n_full, 3)
        Vertices of the full mesh, in mm.
    proxy_points : array_like, shape (n_proxy, 3)
        Vertices of the proxy, in mm.
    proxy_triangles : array_like of int, shape (m_proxy, 3)

    Returns
    -------
    ProxyMapping
    """
    proxy_points, proxy_triangles = validate_mesh_arrays(proxy_points, proxy_triangles, what="the proxy mesh")
    triangle_index, weights, distance = closest_points_on_triangles(full_points, proxy_points, proxy_triangles)
    return ProxyMapping(
        triangle_index=triangle_index,
        vertex_index=proxy_triangles[triangle_index],
        weights=weights,
        distance=distance,
        n_proxy_points=len(proxy_points),
    )


@dataclasses.dataclass(frozen=True, eq=False)
class Decimation:
    """A proxy mesh and the mapping from the full mesh to it.

    Attributes
    ----------
    proxy : TriangleMesh
        The decimated mesh (point data carried from the nearest full vertex; normals recomputed).
    mapping : ProxyMapping
        Full-mesh vertex -> proxy triangle and weights.
    method : str
        The decimation method used, or ``"none"`` when the mesh was already coarse enough.
    target_faces : int
        The triangle count asked for.
    seconds : float
        Wall-clock time of decimation and mapping.
    """

    proxy: TriangleMesh
    mapping: ProxyMapping
    method: str
    target_faces: int
    seconds: float

    def interpolate(self, values_on_proxy) -> np.ndarray:
        """Carry per-vertex values from the proxy to the full mesh (see :meth:`ProxyMapping.interpolate`)."""
        return self.mapping.interpolate(values_on_proxy)

    def gather(self, values_on_full) -> np.ndarray:
        """Carry per-vertex amounts from the full mesh onto the proxy, their sum kept (see
        :meth:`ProxyMapping.gather`)."""
        return self.mapping.gather(values_on_full)


def decimate_mesh(
    mesh,
    *,
    unit=None,
    target_faces: int | None = None,
    target_edge_length: float | None = None,
    method: str = "fast-simplification",
    aggressiveness: float = 7.0,
    memory_limit_bytes: float | None = None,
) -> Decimation:
    """Decimate a mesh to a proxy and map the full mesh onto it.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        The full-resolution mesh (a TriangleMesh: points in mm; a PolyData: in ``unit``, see
        :func:`~translucency.io.polydata.as_triangle_mesh`); not modified.
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from the size).
    target_faces : int, optional
        Triangles wanted in the proxy.
    target_edge_length : float, optional
        Mean proxy edge length in mm (for example derived from the material's diffusion length);
        converted to a triangle count with :func:`target_face_count`. Give exactly one of the two.
    method : {"fast-simplification", "pymeshlab"}
        See :data:`METHODS`.
    aggressiveness : float, default 7
        fast-simplification's ``agg``.
    memory_limit_bytes : float, optional
        What this process and the decimation's children may hold together, bytes (:func:`simplify_arrays`).

    Returns
    -------
    Decimation
        ``proxy``, ``mapping`` and ``interpolate(values_on_proxy)``. When the mesh has no more
        triangles than asked, the proxy is the mesh itself and the mapping is the identity.

    Raises
    ------
    InvalidParameterError
        For a missing or doubled target, an unknown method, or a target that leaves fewer than 20
        triangles.
    """
    started = time.perf_counter()
    mesh = as_triangle_mesh(mesh, unit, entry="decimate_mesh")
    if (target_faces is None) == (target_edge_length is None):
        raise InvalidParameterError("give exactly one of target_faces and target_edge_length to decimate_mesh.")
    if method not in METHODS:
        raise InvalidParameterError(f"unknown decimation method {method!r}; use one of {', '.join(METHODS)}.")
    if target_edge_length is not None:
        area = float(triangle_areas(mesh.points, mesh.triangles).sum())
        target_faces = target_face_count(area, target_edge_length)
        if target_faces < _MIN_FACES:
            longest = math.sqrt(area / (_MIN_FACES * math.sqrt(3.0) / 4.0))
            raise InvalidParameterError(
                f"target_edge_length={target_edge_length} mm would leave {target_faces} triangles on this "
                f"{area:.4g} mm² surface; pass a length below {longest:.3g} mm."
            )
    else:
        if int(target_faces) != target_faces or target_faces < _MIN_FACES:
            raise InvalidParameterError(
                f"target_faces is {target_faces!r}; pass a whole number of at least {_MIN_FACES}."
            )
        target_faces = int(target_faces)

    if target_faces >= mesh.n_triangles:
        proxy, used_method = mesh, "none"
    else:
        points, triangles = simplify_arrays(
            mesh.points,
            mesh.triangles,
            target_faces,
            method=method,
            aggressiveness=aggressiveness,
            memory_limit_bytes=memory_limit_bytes,
        )
        point_data = {}
        carried = {name: values for name, values in mesh.point_data.items() if name != "normals"}
        if carried:  # the nearest full vertex's values (a k-d tree of the full mesh, built only when there are any)
            from scipy.spatial import cKDTree

            _, nearest = cKDTree(mesh.points).query(points)
            point_data = {name: np.asarray(values)[nearest] for name, values in carried.items()}
        if "normals" in mesh.point_data:
            from ..geometry.measure import vertex_normals

            point_data["normals"] = vertex_normals(points, triangles)
        proxy = mesh.replace(points=points, triangles=triangles, point_data=point_data)
        used_method = method
    mapping = map_to_proxy(mesh.points, proxy.points, proxy.triangles)
    return Decimation(
        proxy=proxy,
        mapping=mapping,
        method=used_method,
        target_faces=int(target_faces),
        seconds=time.perf_counter() - started,
    )

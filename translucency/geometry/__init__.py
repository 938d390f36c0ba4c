"""Mesh geometry on plain arrays, shared by :mod:`translucency.io` and :mod:`translucency.scatter`.

No files, no PyVista: ``points`` (n, 3) float64 in mm and ``triangles`` (m, 3) int64 in, arrays out.
This layer imports neither ``io``, ``scatter`` nor ``app``; both ``io`` and ``scatter`` build on it
and never on each other. Import the names from their modules (``translucency.io`` re-exports the
public ones).

=========== ====================================================================
module      concept
=========== ====================================================================
mesh        :class:`TriangleMesh`, the one triangle-mesh record (points in mm)
measure     triangle areas and normals, vertex normals and areas, edge lengths
topology    unique edges, connected components, boundary loops, vertex fans
orientation coherent and outward orientation
proximity   exact closest points on a triangle mesh
morton      Morton (Z-order) curve of a point set
synthetic   generated meshes (icosphere, subdivision, grids, discs) for tests and benchmarks
=========== ====================================================================
"""

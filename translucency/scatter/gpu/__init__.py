"""The optional GPU back end of the pair sums (``pip install "translucency[gpu]"``: numba-cuda).

Nothing here is imported until a solve asks for ``device="gpu"`` or ``"auto"``: :mod:`.probe` says whether
a GPU works (without compiling anything), :mod:`.pairs` sums every (source, receiver) pair on it, for ``exact``
and for relighting's far field, with the CPU's own loops over the sources
(:func:`translucency.scatter.kernels.vertex_sources`, :func:`~translucency.scatter.kernels.indexed_sources`)
compiled for CUDA. The GPU side needs numpy and numba-cuda only: no VTK, PyVista or Embree.
"""

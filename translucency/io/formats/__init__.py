"""One module per mesh file format; :mod:`translucency.io.load` picks the reader by content.

=========================== ============ =========================================================
format                      module       reader
=========================== ============ =========================================================
PLY (ascii, binary LE/BE)   ply          plyfile, with fast paths for triangle lists; ``face``
                                         polygons and ``tristrips`` strips; every vertex property
                                         is kept
OFF (and COFF, NOFF, STOFF) off          translucency's own reader (vertex colours and normals
                                         are kept)
OBJ                         obj          translucency's own reader (vertex colours kept; vertices
                                         are not split at texture seams, unlike VTK's OBJ reader)
STL                         stl          VTK's reader, after a binary file's length is checked
VTK, VTP, VTU, VTM,         vtk          VTK's readers (point arrays are kept; colours as
BYU (.g), glTF, VTK HDF                  ``"colors"``)
3DS, DAE, WRL, X3D, CTM,    pymeshlab    pymeshlab (vertex colours and quality are kept); note that
GTS, PTX, VMI, ...                       pymeshlab drops invalid faces and vertices itself instead
                                         of reporting them
=========================== ============ =========================================================

Each reader takes a path and returns ``(points, triangles, point_data)`` in the file's own unit,
raising :class:`~translucency.errors.MeshError` with one sentence for a file it cannot read;
:mod:`~translucency.io.formats.common` holds what they share.
"""

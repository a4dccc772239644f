@0xe798d40b6f55c8da;
# One cell of a scene store, written unpacked so that workers can mmap it and
# read it in place with FlatArrayMessageReader (no copy, no parse).
using Cxx = import "/capnp/c++.capnp";
$Cxx.namespace("portico::proto");

const cellFormatVersion :UInt32 = 1;

struct CellPortal {
  portalId @0 :UInt32;
  neighborCell @1 :UInt32;
  # Planar convex polygon, xyz per vertex, in order around the polygon.
  polygon @2 :List(Float32);
}

struct CellFile {
  formatVersion @0 :UInt32;
  cellId @1 :UInt32;
  boundsMin @2 :List(Float32);   # xyz
  boundsMax @3 :List(Float32);   # xyz
  vertexCount @4 :UInt64;
  triangleCount @5 :UInt64;
  # Bulk arrays are chunked: a Cap'n Proto list holds fewer than 2^29
  # elements. Position chunks hold whole vertices (xyz); index chunks whole
  # triangles (3 indices into the cell's global vertex numbering); material
  # chunks one id per triangle, aligned with the index chunks.
  positionChunks @6 :List(List(Float32));
  indexChunks @7 :List(List(UInt32));
  materialChunks @8 :List(List(UInt32));
  portals @9 :List(CellPortal);
  # Texture coordinates, uv per vertex, chunked like the positions (whole
  # vertices per chunk); empty when no triangle of the cell is textured.
  # (0, 0) is the image's bottom-left corner, as in OBJ and OpenGL.
  uvChunks @10 :List(List(Float32));
}

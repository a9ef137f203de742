"""Prints what lib3mf reads from a 3MF file, one line per mesh object:
`name vertices triangles beams`. usage: lib3mf_counts.py FILE.3mf"""
import sys

import lib3mf

w = lib3mf.get_wrapper()
m = w.CreateModel()
m.QueryReader("3mf").ReadFromFile(sys.argv[1])
it = m.GetMeshObjects()
while it.MoveNext():
    o = it.GetCurrentMeshObject()
    beams = o.BeamLattice().GetBeamCount()
    print(o.GetName().replace(" ", "_") or "-", o.GetVertexCount(), o.GetTriangleCount(), beams)

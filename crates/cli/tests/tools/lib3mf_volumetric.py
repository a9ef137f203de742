"""Prints what lib3mf reads from a 3MF file with volumetric or implicit
content, one `key value` line each: meshes, levelsets, functions (image and
implicit), images, properties (of the first level set's volume data).
usage: lib3mf_volumetric.py FILE.3mf"""
import sys

import lib3mf


def count(it):
    n = 0
    while it.MoveNext():
        n += 1
    return n


w = lib3mf.get_wrapper()
m = w.CreateModel()
m.QueryReader("3mf").ReadFromFile(sys.argv[1])
print("meshes", count(m.GetMeshObjects()))
print("levelsets", count(m.GetLevelSets()))
print("functions", count(m.GetFunctions()))
print("images", count(m.GetImage3Ds()))
it = m.GetLevelSets()
props = 0
if it.MoveNext():
    vd = it.GetCurrentLevelSet().GetVolumeData()
    if vd is not None:
        props = vd.GetPropertyCount()
print("properties", props)

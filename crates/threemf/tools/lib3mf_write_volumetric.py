"""Writes a 3MF file with lib3mf's own writer: a unit cube mesh carrying
volume data (colour and a `density` property from a function of a 3x2x2
image stack: filter nearest, tile styles clamp/wrap/mirror, offset 0.5,
scale 2) and a level set of an implicit `length(pos)` function bounded by
the cube (channel `shape`, mesh bounding box only, min feature size 0.1).
usage: lib3mf_write_volumetric.py OUT.3mf"""
import struct
import sys
import zlib

import lib3mf


def png_grey(width, height, value):
    def chunk(tag, data):
        crc = zlib.crc32(tag + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", crc)

    rows = b"".join(b"\x00" + bytes([value] * width) for _ in range(height))
    head = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


w = lib3mf.get_wrapper()
m = w.CreateModel()
cube = m.AddMeshObject()
cube.SetName("cube")
for k in range(8):
    p = lib3mf.Position()
    p.Coordinates[0], p.Coordinates[1], p.Coordinates[2] = k & 1, k >> 1 & 1, k >> 2
    cube.AddVertex(p)
for tri in [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
            [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]]:
    t = lib3mf.Triangle()
    t.Indices[0], t.Indices[1], t.Indices[2] = tri
    cube.AddTriangle(t)
# lib3mf 2.5 names the first argument ColumnCount but writes it as
# rowcount: 3 rows (PNG height), 2 columns (PNG width), 2 sheets.
stack = m.AddImageStack(3, 2, 2)
for k in range(2):
    stack.CreateSheetFromBuffer(k, "/3D/volume/sheet%d.png" % k, list(png_grey(2, 3, 100 * k)))
f = m.AddFunctionFromImage3D(stack)
f.SetTileStyles(lib3mf.TextureTileStyle.Clamp, lib3mf.TextureTileStyle.Wrap,
                lib3mf.TextureTileStyle.Mirror)
f.SetFilter(lib3mf.TextureFilter.Nearest)
f.SetOffset(0.5)
f.SetScale(2.0)
g = m.AddImplicitFunction()
g.SetDisplayName("sphere")
g.AddInput("pos", "position", lib3mf.ImplicitPortType.Vector)
n = g.AddLengthNode("len", "length", "")
g.AddLink(g.FindInput("pos"), n.GetInputA())
g.AddOutput("shape", "distance", lib3mf.ImplicitPortType.Scalar)
g.AddLink(n.GetOutputResult(), g.FindOutput("shape"))
vd = m.AddVolumeData()
vd.CreateNewColor(f).SetChannelName("color")
vd.AddPropertyFromFunction("density", f).SetChannelName("red")
ls = m.AddLevelSet()
ls.SetFunction(g)
ls.SetChannelName("shape")
ls.SetMesh(cube)
ls.SetMeshBBoxOnly(True)
ls.SetMinFeatureSize(0.1)
ls.SetVolumeData(vd)
cube.SetVolumeData(vd)
m.AddBuildItem(ls, w.GetIdentityTransform())
m.QueryWriter("3mf").WriteToFile(sys.argv[1])

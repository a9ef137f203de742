"""Prints what lib3mf reads from a 3MF file with volumetric or implicit
content, one `key value` line each:

  warnings N          reader warnings, each also printed as `warning CODE TEXT`
  meshes, levelsets   object counts
  functions, images   function (image and implicit) and image3d counts
  implicitnodes N     nodes over all implicit functions
  sheets N            image sheets over all image stacks
  image ROWS COLUMNS SHEETS
                      one line per image stack, in file order
  properties N        properties of the first level set's volume data
  color 0|1           whether that volume data has a colour
  composite N         its composite's material mappings (-1: none seen)
  meshvolumedata N    mesh objects that carry volume data
  compositesupport 0|1
                      whether this lib3mf implements volumetric composites
                      at all (probed by building one in a scratch model)
  selfwarnings N      warnings lib3mf gives reading back its own file with
                      one image stack and one function from it (written by
                      lib3mf's writer): its reader's own noise per element

usage: lib3mf_volumetric.py FILE.3mf"""
import struct
import sys
import zlib

import lib3mf


def items(it, get):
    out = []
    while it.MoveNext():
        out.append(get(it))
    return out


def composite_support(w):
    m = w.CreateModel()
    group = m.AddBaseMaterialGroup()
    vd = m.AddVolumeData()
    try:
        vd.CreateNewComposite().SetBaseMaterialGroup(group)
        return 1
    except lib3mf.ELib3MFException as e:
        if "not implemented" in str(e):
            return 0
        raise


def png_grey(width, height):
    def chunk(tag, data):
        crc = zlib.crc32(tag + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", crc)

    rows = b"".join(b"\x00" + bytes(width) for _ in range(height))
    head = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


def self_warnings(w):
    m = w.CreateModel()
    stack = m.AddImageStack(2, 2, 1)
    stack.CreateSheetFromBuffer(0, "/3D/volume/s0.png", list(png_grey(2, 2)))
    m.AddFunctionFromImage3D(stack)
    data = m.QueryWriter("3mf").WriteToBuffer()
    back = w.CreateModel()
    r = back.QueryReader("3mf")
    r.ReadFromBuffer(data)
    return r.GetWarningCount()


w = lib3mf.get_wrapper()
m = w.CreateModel()
r = m.QueryReader("3mf")
r.ReadFromFile(sys.argv[1])
n = r.GetWarningCount()
print("warnings", n)
for i in range(n):
    code, text = r.GetWarning(i)
    print("warning", code, text)
meshes = items(m.GetMeshObjects(), lambda it: it.GetCurrentMeshObject())
print("meshes", len(meshes))
levelsets = items(m.GetLevelSets(), lambda it: it.GetCurrentLevelSet())
print("levelsets", len(levelsets))
functions = items(m.GetFunctions(), lambda it: it.GetCurrentFunction())
print("functions", len(functions))
images = items(m.GetImage3Ds(), lambda it: it.GetCurrentImage3D())
print("images", len(images))
nodes = 0
for f in functions:
    if isinstance(f, lib3mf.ImplicitFunction):
        nodes += items(f.GetNodes(), lambda it: 0).__len__()
print("implicitnodes", nodes)
stacks = [i for i in images if isinstance(i, lib3mf.ImageStack)]
print("sheets", sum(i.GetSheetCount() for i in stacks))
for i in stacks:
    print("image", i.GetRowCount(), i.GetColumnCount(), i.GetSheetCount())
props, color, composite = 0, 0, -1
if levelsets:
    vd = levelsets[0].GetVolumeData()
    if vd is not None:
        props = vd.GetPropertyCount()
        color = int(vd.GetColor() is not None)
        c = vd.GetComposite()
        if c is not None:
            composite = c.GetMaterialMappingCount()
print("properties", props)
print("color", color)
print("composite", composite)
print("meshvolumedata", sum(1 for o in meshes if o.GetVolumeData() is not None))
print("compositesupport", composite_support(w))
print("selfwarnings", self_warnings(w))

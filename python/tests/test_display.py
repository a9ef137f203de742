"""Notebook display: a shape shows a rendered image and its bounds, an
analysis report a table with one row per figure. The PNG is decoded here
with the standard library (zlib), no Pillow."""

import base64
import re
import struct
import zlib

import numpy as np
import pytest

import microfrep as mf

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def chunks(png: bytes):
    assert png[:8] == PNG_SIGNATURE
    i = 8
    while i < len(png):
        (n,) = struct.unpack(">I", png[i : i + 4])
        kind = png[i + 4 : i + 8]
        data = png[i + 8 : i + 8 + n]
        (crc,) = struct.unpack(">I", png[i + 8 + n : i + 12 + n])
        assert crc == zlib.crc32(kind + data) & 0xFFFFFFFF, kind
        yield kind, data
        i += 12 + n


def decode_rgb8(png: bytes) -> np.ndarray:
    """An 8-bit RGB, non-interlaced PNG as a height x width x 3 array."""
    cs = list(chunks(png))
    assert cs[0][0] == b"IHDR" and cs[-1][0] == b"IEND"
    w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", cs[0][1])
    assert (depth, colour, interlace) == (8, 2, 0)
    raw = zlib.decompress(b"".join(d for k, d in cs if k == b"IDAT"))
    stride = 3 * w
    assert len(raw) == h * (1 + stride)
    out = np.zeros((h, stride), dtype=np.int32)
    prev = np.zeros(stride, dtype=np.int32)
    for y in range(h):
        f = raw[y * (1 + stride)]
        line = np.frombuffer(raw, dtype=np.uint8, count=stride, offset=y * (1 + stride) + 1).astype(np.int32)
        if f == 0:
            cur = line
        elif f == 2:
            cur = (line + prev) & 255
        else:
            cur = np.zeros(stride, dtype=np.int32)
            for x in range(stride):
                a = cur[x - 3] if x >= 3 else 0
                b = prev[x]
                c = prev[x - 3] if x >= 3 else 0
                if f == 1:
                    pred = a
                elif f == 3:
                    pred = (a + b) // 2
                elif f == 4:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                else:
                    raise AssertionError(f"filter {f}")
                cur[x] = (line[x] + pred) & 255
        out[y] = cur
        prev = cur
    return out.reshape(h, w, 3).astype(np.uint8)


def ihdr_size(png: bytes):
    assert png[:8] == PNG_SIGNATURE
    assert png[12:16] == b"IHDR"
    return struct.unpack(">II", png[16:24])


def test_a_shape_shows_as_a_256_pixel_png_of_its_render():
    s = mf.load("toriball")
    png = s._repr_png_()
    assert isinstance(png, bytes) and png.startswith(PNG_SIGNATURE)
    assert ihdr_size(png) == (256, 256)
    img = decode_rgb8(png)
    # The very pixels of the render (the same ray caster, the model's box).
    assert np.array_equal(img, s.render(size=(256, 256)))
    # Not a blank image: the background and a shaded part.
    assert len({tuple(p) for p in img.reshape(-1, 3)[::97]}) > 10
    # The other sizes and views of render_png are the same images too.
    wide = s.render_png(size=(120, 80), view="top")
    assert ihdr_size(wide) == (120, 80)
    assert np.array_equal(decode_rgb8(wide), s.render(size=(120, 80), view="top"))


def test_the_html_holds_the_image_and_the_bounds():
    s = mf.box((0.25, -1.5, 2.0), (2.75, 3.5, 4.125))
    lo, hi = s.bounds()
    assert (lo, hi) == ((0.25, -1.5, 2.0), (2.75, 3.5, 4.125))
    h = s._repr_html_()
    m = re.search(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)" width="256" height="256"', h)
    assert m, h[:300]
    png = base64.b64decode(m.group(1))
    assert png == s._repr_png_() and ihdr_size(png) == (256, 256)
    text = h[m.end() :]
    assert "bounds x 0.25 .. 2.75, y -1.5 .. 3.5, z 2 .. 4.125 mm" in text, text
    assert "size 2.5 x 5 x 2.125" in text, text


def test_a_shape_without_bounds_explains_instead_of_failing():
    g = mf.gyroid(cell=1.0)
    with pytest.raises(mf.BoundsError):
        g.bounds()
    assert g._repr_png_() is None  # IPython then shows another format
    h = g._repr_html_()
    assert "<img" not in h
    assert "bounds unknown" in h and "with_bounds" in h, h
    # Given bounds, it shows.
    b = g.with_bounds(((0, 0, 0), (1, 1, 1)))
    assert ihdr_size(b._repr_png_()) == (256, 256)
    assert "bounds x 0 .. 1, y 0 .. 1, z 0 .. 1 mm" in b._repr_html_()


def test_a_shape_that_cannot_be_rendered_keeps_its_bounds_line():
    # Nothing inside: the box is known, the ray caster has nothing to show
    # or shows the background; either way no exception reaches the display.
    empty = mf.sphere((0, 0, 0), 1.0).with_bounds(((5, 5, 5), (6, 6, 6)))
    h = empty._repr_html_()
    assert "bounds x 5 .. 6, y 5 .. 6, z 5 .. 6 mm" in h, h


def rows(html):
    body = re.search(r"<tbody>(.*)</tbody>", html, re.S).group(1)
    out = []
    for tr in re.findall(r"<tr>(.*?)</tr>", body, re.S):
        cells = re.findall(r"<t[hd][^>]*>(.*?)</t[hd]>", tr, re.S)
        out.append(cells)
    return out


def test_an_analysis_report_is_a_table_with_one_row_per_figure():
    s = mf.sphere((0, 0, 0), 1.0)
    b = (-1.25, -1.25, -1.25, 1.25, 1.25, 1.25)
    r = s.analyze(resolution=48, bounds=b, connectivity=False, thickness=False)
    assert isinstance(r, dict) and isinstance(r, mf.AnalysisReport)
    t = rows(r._repr_html_())
    names = [c[0] for c in t]
    assert names == ["Volume", "Region volume", "Volume fraction", "Porosity", "Surface area", "Specific surface"]
    assert all(len(c) == 3 for c in t)
    assert t[0][1] == f"{r['volume']['value']:.7g} ± {r['volume']['error']:.2e} mm³"
    assert abs(r["volume"]["value"] - 4 / 3 * np.pi) < 0.05
    assert t[1][1].startswith(f"{2.5 ** 3:.7g} ")
    assert t[3][1].startswith(f"{r['porosity']['value']:.7g} ")

    full = s.analyze(resolution=48, bounds=b)
    t = rows(full._repr_html_())
    names = [c[0] for c in t]
    assert names == [
        "Volume", "Region volume", "Volume fraction", "Porosity", "Surface area", "Specific surface",
        "Solid components", "Pore components", "Open pore fraction", "Closed pores", "Percolation",
        "Euler characteristic", "Thickness", "Pore size",
    ]
    assert len(t) == len(full.figures())
    got = dict((c[0], c[1]) for c in t)
    assert got["Solid components"] == "1" and got["Pore components"] == "1"
    assert got["Closed pores"] == "0" and got["Euler characteristic"] == "1"
    assert got["Percolation"] == "x yes, y yes, z yes"  # the pore space around the ball
    assert got["Thickness"] == f"mean {full['thickness']['solid']['mean']:.7g} mm"
    h = full._repr_html_()
    assert "<caption>analysis of model: 48 x 48 x 48 voxels" in h


def test_a_report_with_an_attribute_and_a_region_adds_their_rows():
    part = mf.box((0, 0, 0), (2, 2, 2))
    m = mf.with_attribute(mf.sphere((1, 1, 1), 0.8), "heat", mf.x)
    r = m.analyze(resolution=32, bounds=(0, 0, 0, 2, 2, 2), region=part, connectivity=False, thickness=False)
    t = rows(r._repr_html_())
    assert [c[0] for c in t][-1] == "Attribute heat"
    assert len(t) == 7 == len(r.figures())
    assert t[0][2].startswith("of the solid, inside region")

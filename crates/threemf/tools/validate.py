"""Validates 3MF model parts against the vendored consortium schemas.

usage: validate.py SCHEMA_DIR (MODEL.xml | PACKAGE.3mf)...

A .3mf argument stands for each of its .model parts (printed as
`PACKAGE.3mf:PART`).

The core schema is loaded with the beam lattice, balls, slice and
volumetric schemas for their namespaces (the core's extension points are
lax wildcards: elements of a loaded namespace are checked against its
global declarations, others, e.g. implicit, are skipped). For models that
use the beam lattice extension, the core's "at least one triangle" is
relaxed, as that extension specifies (a lattice-only mesh has none); for
models with a volumetric level set, the core object's "mesh or components"
is made optional, as the volumetric extension puts a `levelset` there in
their place (it then matches the object's trailing wildcard and is checked).
"""
import os
import sys
import tempfile
import zipfile

import xmlschema

NS = {
    "beamlattice.xsd": "http://schemas.microsoft.com/3dmanufacturing/beamlattice/2017/02",
    "balls.xsd": "http://schemas.microsoft.com/3dmanufacturing/beamlattice/balls/2020/07",
    "slice.xsd": "http://schemas.microsoft.com/3dmanufacturing/slice/2015/07",
    "volumetric.xsd": "http://schemas.3mf.io/3dmanufacturing/volumetric/2022/01",
}


def schema(d, relax, levelset):
    core = open(os.path.join(d, "core.xsd")).read()
    if relax:
        core = core.replace('ref="triangle" minOccurs="1"', 'ref="triangle" minOccurs="0"')
    if levelset:
        old = '<xs:element ref="metadatagroup" minOccurs="0" maxOccurs="1"/>\n\t\t\t<xs:choice>'
        assert old in core, "core.xsd: CT_Object layout changed"
        core = core.replace(old, old[: -len("<xs:choice>")] + '<xs:choice minOccurs="0">')
    imports = "".join(
        f'<xs:import namespace="{ns}" schemaLocation="{os.path.join(os.path.abspath(d), f)}"/>'
        for f, ns in NS.items()
    )
    core = core.replace("blockDefault=\"#all\">", "blockDefault=\"#all\">" + imports, 1)
    with tempfile.NamedTemporaryFile("w", suffix=".xsd", delete=False, dir=d) as t:
        t.write(core)
        name = t.name
    try:
        return xmlschema.XMLSchema(name)
    finally:
        os.unlink(name)


def parts(args):
    for a in args:
        if a.endswith(".3mf"):
            with zipfile.ZipFile(a) as z:
                for n in z.namelist():
                    if n.endswith(".model"):
                        yield f"{a}:{n}", z.read(n).decode("utf-8")
        else:
            yield a, open(a, encoding="utf-8").read()


def main():
    d = sys.argv[1]
    schemas = {}
    bad = 0
    for f, text in parts(sys.argv[2:]):
        key = ("beamlattice/2017/02" in text, ":levelset " in text)
        if key not in schemas:
            schemas[key] = schema(d, *key)
        s = schemas[key]
        errors = list(s.iter_errors(text))
        for e in errors[:5]:
            print(f"{f}: {e.reason} at {e.path}")
        bad += bool(errors)
        print(f"{f}: {'INVALID' if errors else 'valid'}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()

"""Validates 3MF model parts against the vendored consortium schemas.

usage: validate.py SCHEMA_DIR MODEL.xml...

The core schema is loaded with the beam lattice, balls and slice schemas
for their namespaces (the core's extension points are lax wildcards, so
elements of other namespaces, e.g. volumetric, are not checked). For models
that use the beam lattice extension, the core's "at least one triangle" is
relaxed, as that extension specifies (a lattice-only mesh has none).
"""
import os
import sys
import tempfile

import xmlschema

NS = {
    "beamlattice.xsd": "http://schemas.microsoft.com/3dmanufacturing/beamlattice/2017/02",
    "balls.xsd": "http://schemas.microsoft.com/3dmanufacturing/beamlattice/balls/2020/07",
    "slice.xsd": "http://schemas.microsoft.com/3dmanufacturing/slice/2015/07",
}


def schema(d, relax):
    core = open(os.path.join(d, "core.xsd")).read()
    if relax:
        core = core.replace('ref="triangle" minOccurs="1"', 'ref="triangle" minOccurs="0"')
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


def main():
    d, files = sys.argv[1], sys.argv[2:]
    strict, relaxed = schema(d, False), schema(d, True)
    bad = 0
    for f in files:
        text = open(f, encoding="utf-8").read()
        s = relaxed if "beamlattice/2017/02" in text else strict
        errors = list(s.iter_errors(f))
        for e in errors[:5]:
            print(f"{f}: {e.reason} at {e.path}")
        bad += bool(errors)
        print(f"{f}: {'INVALID' if errors else 'valid'}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()

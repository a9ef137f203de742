"""PoreSpy's side of the local-thickness comparisons (bench suite `analyze`
and the optional test crates/analysis/tests/porespy.rs).

usage: porespy_thickness.py LABELS.raw NX NY NZ PHASE [FIELD_OUT.raw]

LABELS.raw: one byte per voxel, x fastest then y then z (microfrep's order),
1 = pore, 2 = solid. PHASE: 1 or 2, the phase measured. Prints one JSON line:
porosity (pore voxels / all), wall and CPU seconds of the local_thickness
call, peak resident memory of its process, and the diameter distribution over the
phase's voxels in voxel units (PoreSpy returns radii; diameter = 2 radius).
With FIELD_OUT the per-voxel diameters (float32, same order) are written.
"""

import json
import resource
import sys
import time

import numpy as np


def main():
    path, nx, ny, nz, phase = sys.argv[1:6]
    nx, ny, nz, phase = int(nx), int(ny), int(nz), int(phase)
    import porespy

    labels = np.fromfile(path, dtype=np.uint8).reshape((nz, ny, nx))
    mask = labels == phase
    before = resource.getrusage(resource.RUSAGE_SELF)
    t0 = time.perf_counter()
    radius = porespy.filters.local_thickness(mask)
    seconds = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_SELF)
    base_kib, peak_kib = before.ru_maxrss, after.ru_maxrss
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    dia = 2.0 * np.asarray(radius, dtype=np.float64)[mask]
    out = {
        "porespy": porespy.__version__,
        "porosity": float(np.mean(labels == 1)),
        "seconds": seconds,
        "cpu_seconds": cpu,
        "peak_mib": peak_kib / 1024.0,
        "before_mib": base_kib / 1024.0,
        "voxels": int(mask.sum()),
    }
    if dia.size:
        out.update(
            mean=float(dia.mean()),
            median=float(np.percentile(dia, 50, method="inverted_cdf")),
            p10=float(np.percentile(dia, 10, method="inverted_cdf")),
            p90=float(np.percentile(dia, 90, method="inverted_cdf")),
            max=float(dia.max()),
        )
    if len(sys.argv) > 6:
        (2.0 * np.asarray(radius, dtype=np.float32)).astype(np.float32).tofile(sys.argv[6])
    print(json.dumps(out))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Convert the CUReT BRDF database (abrdf.dat, table.txt; see SOURCE.txt) to one CSV that
goniofit reads: group = CUReT sample number (1-61), angles in degrees in goniofit's
convention (theta_i, theta_r from the normal; phi_r from the plane of incidence, 0 = the
forward/specular side), L = the BRDF value as CUReT gives it (mean of R, G, B; 1/sr); the
comment line `# quantity: brdf` tells goniofit that L is a BRDF.

CUReT's azimuths are those of direction vectors pointing away from the surface, so the mirror
of the source at phi_i is phi_v = phi_i + pi: theta_r = theta_v,
phi_r = wrap(phi_v - phi_i - pi) into (-180, 180] degrees.

Usage: python3 convert.py ABRDF_DAT TABLE_TXT > curet.csv   (standard library only)
"""
import math
import sys


def wrap_deg(a):
    """Wrap an angle in degrees into (-180, 180]."""
    a = math.fmod(a, 360.0)
    if a <= -180.0:
        a += 360.0
    elif a > 180.0:
        a -= 360.0
    return a


def main(abrdf_path, table_path):
    geos = []
    with open(table_path, newline="") as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            idx, tv, pv, ti, pi_ = int(fields[0]), *map(float, fields[1:5])
            assert idx == len(geos) + 1, f"table.txt: index {idx} out of order"
            geos.append((ti, tv, pv, pi_))
    assert len(geos) == 205, f"table.txt: {len(geos)} geometries, expected 205"
    out = sys.stdout
    out.write("# CUReT BRDF database (Dana et al. 1999), converted by data/curet/convert.py;\n")
    out.write("# see data/curet/SOURCE.txt. Angles in degrees, goniofit's convention.\n")
    out.write("# quantity: brdf\n")
    out.write("group,theta_i,theta_r,phi_r,L\n")
    n_rows = 0
    with open(abrdf_path) as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            sample = int(fields[0])
            values = fields[1:]
            assert len(values) == 205, f"abrdf.dat: sample {sample} has {len(values)} values"
            for (ti, tv, pv, pi_), v in zip(geos, values):
                phi_r = wrap_deg(math.degrees(pv - pi_ - math.pi))
                out.write(
                    f"{sample},{math.degrees(ti):.6f},{math.degrees(tv):.6f},{phi_r:.6f},{v}\n"
                )
            n_rows += 1
    assert n_rows == 61, f"abrdf.dat: {n_rows} samples, expected 61"


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])

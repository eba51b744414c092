#!/usr/bin/env python3
"""Writes Type A and Type B IES fixtures (tests/data/fixtures/type_*.ies) sampled from one analytic,
asymmetric distribution given in lumiview's luminaire frame, so tests can check the conversion into
the Type C frame against the formula rather than against our own code.

Frame (docs/photometry.md): nadir -Z, C0 +X (length), C90 +Y (width). LM-63-2002 section 3: in
Types A and B photometric horizontal is H = V = 0 (lumiview: C0, +X), nadir is V = -90, and
horizontal angles run clockwise seen from above (towards -Y):
  Type A: polar axis vertical:   d = (cos V cos H, -cos V sin H, sin V)
  Type B: polar axis along Y:    d = (cos H cos V, -sin H, cos H sin V)
The distribution, a floodlight aimed along +X:
  I(d) = 1000 * max(0, d.x)^2 * (1 + 0.5 d.z + 0.25 d.y) cd
(for the laterally symmetric file the d.y term is dropped). It integrates to 2000*pi/3 lm.

Run from the repository root: python3 scripts/make-typeab-fixtures.py
"""
import math

OUT = "tests/data/fixtures"


def intensity(d, lateral_symmetric=False):
    ahead = max(0.0, d[0])
    k = 0.0 if lateral_symmetric else 0.25
    return 1000.0 * ahead * ahead * (1.0 + 0.5 * d[2] + k * d[1])


def dir_b(h, v):
    h, v = math.radians(h), math.radians(v)
    return (math.cos(h) * math.cos(v), -math.sin(h), math.cos(h) * math.sin(v))


def dir_a(h, v):
    h, v = math.radians(h), math.radians(v)
    return (math.cos(v) * math.cos(h), -math.cos(v) * math.sin(h), math.sin(v))


def write(path, ptype, h_angles, v_angles, dirf, lateral):
    lines = [
        "IESNA:LM-63-2002",
        f"[TEST] Type {'B' if ptype == 2 else 'A'} fixture from scripts/make-typeab-fixtures.py",
        "[LUMINAIRE] analytic floodlight",
        "TILT=NONE",
        f"1 -1 1.0 {len(v_angles)} {len(h_angles)} {ptype} 2 0.2 0.2 0",
        "1.0 1.0 100",
        " ".join(f"{v:g}" for v in v_angles),
        " ".join(f"{h:g}" for h in h_angles),
    ]
    for h in h_angles:
        vals = [f"{intensity(dirf(h, v), lateral):.4f}" for v in v_angles]
        for i in range(0, len(vals), 10):
            lines.append(" ".join(vals[i : i + 10]))
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


def main():
    full = [-90.0 + 5.0 * i for i in range(37)]
    half = [5.0 * i for i in range(19)]
    write(f"{OUT}/type_b.ies", 2, full, full, dir_b, False)
    write(f"{OUT}/type_b_lateral.ies", 2, half, full, dir_b, True)
    write(f"{OUT}/type_a.ies", 3, full, full, dir_a, False)


if __name__ == "__main__":
    main()

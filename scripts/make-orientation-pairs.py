#!/usr/bin/env python3
"""Writes tests/data/pairs/: the same luminaires as IES LM-63-2002 and as EULUMDAT, written
independently of lumiview's Rust code, for the orientation tests in tests/photometry_files.rs.

Each pair samples one analytic, deliberately asymmetric intensity distribution f(C, gamma) (cd;
lumiview's Type C frame: gamma from nadir, C counter-clockwise from C0 seen from above) made
symmetric as the pair's symmetry requires, at the same grid nodes:

  full      IES horizontal 0..345 (no 360 entry)     LDT Isym 0
  c0c180    IES horizontal 0..180                    LDT Isym 2 (C0..C180 stored)
  c90c270   IES horizontal 90..270                   LDT Isym 3 (C270..C0..C90 stored)
  quadrant  IES horizontal 0..90                     LDT Isym 4 (C0..C90 stored)
  rotational IES one horizontal angle                LDT Isym 1

The pairs' luminous openings are the same rectangle too: 0.6 m along X (C0-C180) and 0.3 m along Y
(C90-C270). IES puts its length along X, EULUMDAT its length along Y (docs/adr/0002), so the IES
file says width 0.3, length 0.6 and the EULUMDAT file length 300 mm, width 600 mm.

plus `rotated90.ies`: the `full` luminaire turned 90 degrees counter-clockwise about the vertical
axis (its C0 plane now at C90), and `luxcore_ASA_15M_R2.ldt`: the real IES file
tests/data/misc/luxcore_ASA_15M_R2.ies converted by hand to EULUMDAT (cd -> cd/klm with its
13000 lm lamp, Isym 2).

It also writes tests/data/fixtures/side_lit.ldt, the asymmetric side-lit luminaire of the
orientation tests and goldens: EULUMDAT Isym 0, luminous area 600 mm long (Y) x 150 mm wide (X)
with side heights C0 60, C90 30, C180 0, C270 15 mm, housing 620 x 170 x 80 mm, and an intensity
that differs on every side (`side_lit`).

Run from the repository root: python3 scripts/make-orientation-pairs.py
"""
import math
import os

OUT = "tests/data/pairs"
LAMP_FLUX = 8000.0  # lm, for the EULUMDAT files (values in cd/klm); the pairs emit 6963 lm, LOR 87 %
DC = 15.0
DG = 5.0


def f(c_deg, g_deg):
    c = math.radians(c_deg)
    g = math.radians(g_deg)
    down = 900.0 * ((1.0 + math.cos(g)) / 2.0) ** 3
    side = 400.0 * math.sin(g) * (1.0 + 0.7 * math.cos(c - math.radians(30.0))) * (1.0 + 0.3 * math.sin(2 * c))
    up = 60.0 * max(0.0, -math.cos(g))
    return down + side + up


def sym(kind):
    if kind == "full":
        return f
    if kind == "c0c180":
        return lambda c, g: 0.5 * (f(c, g) + f(360.0 - c, g))
    if kind == "c90c270":
        return lambda c, g: 0.5 * (f(c, g) + f(180.0 - c, g))
    if kind == "quadrant":
        return lambda c, g: 0.25 * (f(c, g) + f(360.0 - c, g) + f(180.0 - c, g) + f(180.0 + c, g))
    if kind == "rotational":
        return lambda c, g: sum(f(k * 15.0, g) for k in range(24)) / 24.0
    raise ValueError(kind)


GAMMAS = [i * DG for i in range(int(180 / DG) + 1)]


def ies_h_angles(kind):
    if kind == "full":
        return [i * DC for i in range(24)]
    if kind == "c0c180":
        return [i * DC for i in range(13)]
    if kind == "c90c270":
        return [90.0 + i * DC for i in range(13)]
    if kind == "quadrant":
        return [i * DC for i in range(7)]
    return [0.0]


def fmt(v):
    return f"{v:.4f}"


def write_ies(path, title, h_angles, func, width=0.3, length=0.6):
    lines = [
        "IESNA:LM-63-2002",
        "[TEST] lumiview orientation pair",
        "[MANUFAC] lumiview test data",
        f"[LUMINAIRE] {title}",
        "TILT=NONE",
        f"1 -1 1.0 {len(GAMMAS)} {len(h_angles)} 1 2 {width} {length} 0",
        "1.0 1.0 50",
        " ".join(fmt(g) for g in GAMMAS),
        " ".join(fmt(h) for h in h_angles),
    ]
    for h in h_angles:
        vals = [fmt(func(h, g)) for g in GAMMAS]
        for i in range(0, len(vals), 10):
            lines.append(" ".join(vals[i : i + 10]))
    with open(path, "w", newline="\r\n") as fh:
        fh.write("\n".join(lines) + "\n")


def ldt_planes(isym, mc):
    if isym == 0:
        return list(range(mc))
    if isym == 1:
        return [0]
    if isym == 2:
        return list(range(mc // 2 + 1))
    if isym == 3:
        # Symmetric about C90-C270: stored from C270 through C0 to C90.
        return list(range(3 * mc // 4, mc)) + list(range(0, mc // 4 + 1))
    return list(range(mc // 4 + 1))


def write_ldt(path, title, isym, c_angles, gammas, cd_func, lamp_flux, length_mm=300, width_mm=600,
              lor=100.0, comma=False, heights_mm=(0, 0, 0, 0), luminaire_mm=None):
    mc = len(c_angles)
    dc = c_angles[1] - c_angles[0] if mc > 1 else 0
    ng = len(gammas)
    dg = gammas[1] - gammas[0]

    def num(v):
        s = f"{v:.4f}" if isinstance(v, float) else str(v)
        return s.replace(".", ",") if comma else s

    lines = [
        "lumiview test data",
        "1",
        str(isym),
        str(mc),
        num(float(dc)),
        str(ng),
        num(float(dg)),
        "lumiview orientation pair",
        title,
        "PAIR-1",
        os.path.basename(path),
        "2026-11-22 lumiview",
        *[str(v) for v in (luminaire_mm or (length_mm, width_mm, 50))],
        str(length_mm), str(width_mm), *[str(h) for h in heights_mm],
        num(100.0), num(lor), num(1.0), num(0.0),
        "1",
        "1", "Test lamp", num(lamp_flux), "3000K", "80", num(50.0),
    ]
    lines += [num(0.5)] * 10
    lines += [num(c) for c in c_angles]
    lines += [num(g) for g in gammas]
    for p in ldt_planes(isym, mc):
        c = c_angles[p]
        for g in gammas:
            lines.append(num(cd_func(c, g) * 1000.0 / lamp_flux))
    with open(path, "w", newline="\r\n") as fh:
        fh.write("\n".join(lines) + "\n")


def read_ies_table(path):
    with open(path, encoding="latin-1") as fh:
        text = fh.read().splitlines()
    i = next(k for k, l in enumerate(text) if l.startswith("TILT="))
    toks = " ".join(text[i + 1 :]).replace(",", " ").split()
    vals = [float(t) for t in toks]
    nv, nh = int(vals[3]), int(vals[4])
    lamp_lm = vals[0] * vals[1]
    p = 13
    v = vals[p : p + nv]
    p += nv
    h = vals[p : p + nh]
    p += nh
    table = [vals[p + k * nv : p + (k + 1) * nv] for k in range(nh)]
    return v, h, table, lamp_lm


def main():
    os.makedirs(OUT, exist_ok=True)
    isyms = {"full": 0, "c0c180": 2, "c90c270": 3, "quadrant": 4, "rotational": 1}
    for kind, isym in isyms.items():
        func = sym(kind)
        write_ies(f"{OUT}/{kind}.ies", f"pair {kind}", ies_h_angles(kind), func)
        c_angles = [i * DC for i in range(24)] if isym != 1 else [0.0]
        write_ldt(f"{OUT}/{kind}.ldt", f"pair {kind}", isym, c_angles, GAMMAS, func, LAMP_FLUX,
                  lor=87.0, comma=(kind == "c0c180"))
    # The full luminaire turned 90 degrees counter-clockwise: what was at C now lies at C + 90.
    write_ies(f"{OUT}/rotated90.ies", "pair full rotated 90", ies_h_angles("full"),
              lambda c, g: f(c - 90.0, g), width=0.6, length=0.3)
    # A real file converted by hand: IES 0..180 (cd) -> EULUMDAT Isym 2 (cd/klm).
    v, h, table, lamp_lm = read_ies_table("tests/data/misc/luxcore_ASA_15M_R2.ies")
    step = h[1] - h[0]
    c_angles = [i * step for i in range(int(round(360 / step)))]
    lookup = {round(hh, 6): row for hh, row in zip(h, table)}

    def cd(c, g):
        return lookup[round(c, 6)][v.index(g)]

    write_ldt(f"{OUT}/luxcore_ASA_15M_R2.ldt", "ASA 15M R2 (converted from IES)", 2, c_angles, v, cd,
              lamp_lm, length_mm=378, width_mm=378, lor=73.5)
    # The side-lit luminaire: brightest towards C0, then C90, C270, C180 near the horizontal.
    gammas = [i * 5.0 for i in range(19)]
    write_ldt("tests/data/fixtures/side_lit.ldt", "side-lit test luminaire", 0,
              [i * DC for i in range(24)], gammas, side_lit, 1500.0, length_mm=600, width_mm=150,
              lor=89.1, heights_mm=(60, 30, 0, 15), luminaire_mm=(620, 170, 80))


def side_lit(c_deg, g_deg):
    """cd: a downlight plus side light that differs by azimuth (C0 > C90 > C270 > C180)."""
    c = math.radians(c_deg)
    g = math.radians(g_deg)
    side = 1.0 + 0.6 * math.cos(c) + 0.25 * math.sin(c)
    return 300.0 * math.cos(g) + 80.0 * math.sin(g) * side


if __name__ == "__main__":
    main()

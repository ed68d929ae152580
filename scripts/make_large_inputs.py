#!/usr/bin/env python3
"""Builds the large inputs of the speed tables in docs/performance.md (section "CPU engine on the
2-core development machine"; issue 12, section 3); they are not committed, this script is.

  python3 scripts/make_large_inputs.py [OUT_DIR]      (default: target/large)

writes
  chaperonin_129k.pdb  79 copies of tests/data/1hpv.pdb (128,849 atoms) on a 5 x 4 x 4 lattice,
                       each copy with its own two chain IDs (A-Z, a-z, 0-9, cycling after 31
                       copies), serials renumbered (hybrid-36 past 99,999, as chemfiles and
                       cctbx write them), TER records and the ligand's CONECT records per copy.
  adk_box_1m.xyz       300 copies of tests/data/adk_open.pdb (1,002,300 atoms), each randomly
                       rotated (fixed seed) on a 7 x 7 x 7 lattice of 44 A spacing: a crowded
                       box. Names are elements (first letter of the PDB atom name).

Coordinates are in Angstrom. Only the standard library is used.
"""

import math
import os
import random
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CHAINS = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789"
DIGITS_UPPER = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ"


def hybrid36(width, value):
    """Encodes a non-negative integer in hybrid-36 (decimal up to 10**width - 1)."""
    if value < 10**width:
        return str(value).rjust(width)
    value -= 10**width
    value += 10 * 36 ** (width - 1)
    out = ""
    for _ in range(width):
        value, d = divmod(value, 36)
        out = DIGITS_UPPER[d] + out
    return out


def atom_lines(path):
    """(record lines, CONECT lines) of the first model of a PDB file."""
    atoms, conect = [], []
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if line.startswith(("ATOM  ", "HETATM", "TER")):
                atoms.append(line)
            elif line.startswith("CONECT"):
                conect.append(line)
            elif line.startswith("ENDMDL"):
                break
    return atoms, conect


def make_pdb(out):
    atoms, conect = atom_lines(os.path.join(ROOT, "tests/data/1hpv.pdb"))
    copies, spacing = 79, 70.0
    serial = 0
    with open(out, "w") as f:
        f.write("REMARK   a chaperonin-sized assembly: 79 tiled copies of 1HPV\n")
        f.write("CRYST1  400.000  300.000  300.000  90.00  90.00  90.00 P 1           1\n")
        for c in range(copies):
            shift = (spacing * (c % 5), spacing * ((c // 5) % 4), spacing * (c // 20))
            chain_map = {"A": CHAINS[(2 * c) % 62], "B": CHAINS[(2 * c + 1) % 62], " ": " "}
            renumber = {}
            for line in atoms:
                line = line[:72].ljust(72) if line.startswith("TER") else line
                serial += 1
                old = line[6:11].strip()
                if old:
                    renumber[old] = serial
                chain = chain_map.get(line[21], line[21]) if len(line) > 21 else " "
                if line.startswith("TER"):
                    f.write(f"TER   {hybrid36(5, serial)}{line[11:21]}{chain}{line[22:]}\n")
                    continue
                xyz = [float(line[30 + 8 * k : 38 + 8 * k]) + shift[k] for k in range(3)]
                coords = "".join(f"{v:8.3f}" for v in xyz)
                f.write(f"{line[:6]}{hybrid36(5, serial)}{line[11:21]}{chain}{line[22:30]}"
                        f"{coords}{line[54:]}\n")
            for line in conect:
                fields = [line[6 + 5 * k : 11 + 5 * k].strip() for k in range(5)]
                mapped = [hybrid36(5, renumber[s]) for s in fields if s in renumber]
                f.write("CONECT" + "".join(mapped) + "\n")
        f.write("END\n")


def rotation(rng):
    """A uniformly random rotation matrix (from a random unit quaternion)."""
    u1, u2, u3 = rng.random(), rng.random(), rng.random()
    a, b = math.sqrt(1 - u1), math.sqrt(u1)
    w, x = a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2)
    y, z = b * math.sin(2 * math.pi * u3), b * math.cos(2 * math.pi * u3)
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]


def make_xyz(out):
    atoms, _ = atom_lines(os.path.join(ROOT, "tests/data/adk_open.pdb"))
    atoms = [a for a in atoms if a.startswith(("ATOM  ", "HETATM"))]
    names = [a[12:16].strip()[0] for a in atoms]
    xyz = [[float(a[30 + 8 * k : 38 + 8 * k]) for k in range(3)] for a in atoms]
    centre = [sum(p[k] for p in xyz) / len(xyz) for k in range(3)]
    local = [[p[k] - centre[k] for k in range(3)] for p in xyz]
    rng = random.Random(12)
    copies, side, spacing = 300, 7, 44.0
    with open(out, "w") as f:
        f.write(f"{copies * len(atoms)}\n")
        f.write("300 AdK copies in a crowded box (mdsurf scripts/make_large_inputs.py)\n")
        for c in range(copies):
            m = rotation(rng)
            shift = (spacing * (c % side), spacing * ((c // side) % side),
                     spacing * (c // (side * side)))
            lines = []
            for name, p in zip(names, local):
                q = [m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + shift[r] for r in range(3)]
                lines.append(f"{name} {q[0]:.3f} {q[1]:.3f} {q[2]:.3f}\n")
            f.write("".join(lines))


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target/large")
    os.makedirs(out_dir, exist_ok=True)
    make_pdb(os.path.join(out_dir, "chaperonin_129k.pdb"))
    make_xyz(os.path.join(out_dir, "adk_box_1m.xyz"))
    print(f"wrote {out_dir}/chaperonin_129k.pdb and {out_dir}/adk_box_1m.xyz")


if __name__ == "__main__":
    main()

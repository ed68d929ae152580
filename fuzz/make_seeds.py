"""Writes the fuzz seeds in fuzz/seeds/ (run from the repository root: python3 fuzz/make_seeds.py).

Text seeds are cut from tests/data; DCD and Amber NetCDF seeds are written byte by byte. The
XTC and TRR seeds were made once with gmx trjconv from md_1u19.xtc (20 and 5 atoms) and are
committed as they are (see docs/fuzzing.md)."""
import gzip, bz2, struct, os, re
D='tests/data'; S='fuzz/seeds'
def out(t, name, data):
    os.makedirs(f'{S}/{t}', exist_ok=True)
    if isinstance(data, str): data = data.encode()
    open(f'{S}/{t}/{name}','wb').write(data)

# PDB: header records, first atoms, TER/END; a ligand with CONECT; two models.
lines = open(f'{D}/adk_open.pdb').read().splitlines()
atoms = [l for l in lines if l.startswith(('ATOM','HETATM'))]
head = [l for l in lines if l.startswith(('CRYST1','REMARK 290','HEADER','TITLE'))][:6]
out('pdb','adk_head.pdb','\n'.join(head + atoms[:40] + ['TER','END'])+'\n')
lines = open(f'{D}/1hpv.pdb').read().splitlines()
het = [l for l in lines if l.startswith('HETATM')][:30]
serials = {int(l[6:11]) for l in het}
conect = [l for l in lines if l.startswith('CONECT') and int(l[6:11]) in serials]
cryst = [l for l in lines if l.startswith(('CRYST1','SCALE','ORIGX'))]
atom = [l for l in lines if l.startswith('ATOM')][:20]
out('pdb','1hpv_ligand.pdb','\n'.join(cryst + atom + ['TER'] + het + conect + ['END'])+'\n')
models = ['MODEL        1'] + atoms[:10] + ['ENDMDL','MODEL        2'] + atoms[:10] + ['ENDMDL','END']
out('pdb','two_models.pdb','\n'.join(models)+'\n')

# mmCIF: data block, cell, the atom_site loop cut to 40 rows, struct_conn when present.
text = gzip.open(f'{D}/1a7g.cif.gz','rt').read().splitlines()
blocks, cur = [], []
for l in text[1:]:
    if l.startswith('#'):
        if cur: blocks.append(cur)
        cur = []
    else:
        cur.append(l)
if cur: blocks.append(cur)
keep = [text[0]]
for b in blocks:
    body = [l for l in b if l != 'loop_']
    if any(l.startswith('_cell.') for l in body):
        keep += ['#'] + b
    elif any(l.startswith('_atom_site.') for l in body):
        header = [l for l in b if l == 'loop_' or l.startswith('_')]
        rows = [l for l in b if not (l == 'loop_' or l.startswith('_'))]
        keep += ['#'] + header + rows[:30] + [r for r in rows if r.startswith('HETATM')][:10]
    elif any(l.startswith('_struct_conn.') for l in body):
        header = [l for l in b if l == 'loop_' or l.startswith('_')]
        rows = [l for l in b if not (l == 'loop_' or l.startswith('_'))]
        keep += ['#'] + header + rows[:4]
keep.append('#')
out('mmcif','1a7g_head.cif','\n'.join(keep)+'\n')

# GRO: 20 atoms with velocities, 20 without, two frames, a triclinic box.
def gro_head(path, n, box=None):
    ls = open(path).read().splitlines()
    return [ls[0], f'{n:5d}'] + ls[2:2+n] + [box or ls[-1]]
out('gro','md_1u19_vel.gro','\n'.join(gro_head(f'{D}/md_1u19.gro',20))+'\n')
a = gro_head(f'{D}/adk_oplsaa.gro',20)
out('gro','adk_head.gro','\n'.join(a)+'\n')
out('gro','two_frames.gro','\n'.join(a + a)+'\n')
out('gro','triclinic.gro','\n'.join(gro_head(f'{D}/martini_dppc_chol_bilayer.gro',15,
    '   5.00000   5.00000   5.00000   0.00000   0.00000   1.00000   0.00000   1.00000   1.00000'))+'\n')

# XYZ: plain, two frames, extended (Lattice, Properties).
xyz = '3\nwater\nO 0.0 0.0 0.0\nH 0.76 0.59 0.0\nH -0.76 0.59 0.0\n'
out('xyz','water.xyz', xyz)
out('xyz','two_frames.xyz', xyz + xyz.replace('0.59','0.61'))
out('xyz','extended.xyz','2\nLattice="10 0 0 0 10 0 0 0 10" Properties=species:S:1:pos:R:3 time=1.5\nC 1 2 3\nO 4 5 6\n')

# LAMMPS dump: the first frame cut to 20 atoms, twice; a triclinic box with element column.
ls = bz2.open(f'{D}/spce_all_coords.lammpstrj.bz2','rt').read().splitlines()
frame = ls[:3] + ['20'] + ls[4:9] + ls[9:29]
out('lammps','spce_head.lammpstrj','\n'.join(frame)+'\n')
second = list(frame); second[1] = '10'
out('lammps','two_frames.lammpstrj','\n'.join(frame + second)+'\n')
out('lammps','triclinic.lammpstrj','\n'.join(['ITEM: TIMESTEP','0','ITEM: NUMBER OF ATOMS','3',
    'ITEM: BOX BOUNDS xy xz yz pp pp pp','0 10 1','0 10 0','0 10 0.5',
    'ITEM: ATOMS id type element xs ys zs','1 1 O 0.1 0.2 0.3','2 2 H 0.2 0.2 0.3','3 2 H 0.1 0.3 0.3'])+'\n')

# DCD (CHARMM): 5 atoms, 2 frames, with and without a unit cell; plus the first frame of adk.
def rec(payload): return struct.pack('<i', len(payload)) + payload + struct.pack('<i', len(payload))
def dcd(natoms, frames, cell):
    icntrl = [0]*20
    icntrl[0] = frames; icntrl[1] = 0; icntrl[2] = 1; icntrl[3] = frames
    icntrl[10] = 1 if cell else 0; icntrl[19] = 24
    h = b'CORD' + struct.pack('<9i', *icntrl[:9]) + struct.pack('<f', 0.02) + struct.pack('<10i', *icntrl[10:])
    out_ = rec(h) + rec(struct.pack('<i', 1) + b'fuzz seed'.ljust(80)) + rec(struct.pack('<i', natoms))
    for k in range(frames):
        if cell:
            out_ += rec(struct.pack('<6d', 20.0+k, 90.0, 21.0, 90.0, 90.0, 22.0))
        for axis in range(3):
            out_ += rec(struct.pack(f'<{natoms}f', *[i + axis + 0.5*k for i in range(natoms)]))
    return out_
out('dcd','cell.dcd', dcd(5, 2, True))
out('dcd','nocell.dcd', dcd(5, 2, False))

# Amber NetCDF (classic CDF-1): 4 atoms, 2 frames, coordinates, time and a box.
def nc(natoms, frames, cdf=1):
    def name(s):
        b = s.encode(); return struct.pack('>i', len(b)) + b + b'\0'*((-len(b)) % 4)
    def att_text(k, v):
        b = v.encode(); return name(k) + struct.pack('>ii', 2, len(b)) + b + b'\0'*((-len(b)) % 4)
    NC_DIM, NC_VAR, NC_ATT = 10, 11, 12
    dims = [('frame', 0), ('spatial', 3), ('atom', natoms), ('cell_spatial', 3), ('cell_angular', 3), ('label', 5)]
    # name, dim ids, type (2 char, 5 float, 6 double), attributes, is record
    vars_ = [('spatial', [1], 2, [], False), ('cell_spatial', [3], 2, [], False),
             ('cell_angular', [4, 5], 2, [], False),
             ('time', [0], 5, [('units', 'picosecond')], True),
             ('coordinates', [0, 2, 1], 5, [('units', 'angstrom')], True),
             ('cell_lengths', [0, 3], 6, [('units', 'angstrom')], True),
             ('cell_angles', [0, 4], 6, [('units', 'degree')], True)]
    size = {2: 1, 5: 4, 6: 8}
    def vsize(v):
        n = size[v[2]]
        for d in v[1]:
            if dims[d][1]: n *= dims[d][1]
        return n
    pad = lambda n: n + (-n) % 4
    gatts = [('Conventions', 'AMBER'), ('ConventionVersion', '1.0'), ('program', 'fuzz seed')]
    def header(begins):
        h = b'CDF' + bytes([cdf]) + struct.pack('>i', frames)
        h += struct.pack('>ii', NC_DIM, len(dims)) + b''.join(name(n) + struct.pack('>i', l) for n, l in dims)
        h += struct.pack('>ii', NC_ATT, len(gatts)) + b''.join(att_text(k, v) for k, v in gatts)
        h += struct.pack('>ii', NC_VAR, len(vars_))
        for v, b in zip(vars_, begins):
            h += name(v[0]) + struct.pack('>i', len(v[1])) + b''.join(struct.pack('>i', d) for d in v[1])
            h += (struct.pack('>ii', NC_ATT, len(v[3])) + b''.join(att_text(k, x) for k, x in v[3])) if v[3] else struct.pack('>ii', 0, 0)
            h += struct.pack('>ii', v[2], pad(vsize(v)))
            h += struct.pack('>i', b) if cdf == 1 else struct.pack('>q', b)
        return h
    hlen = len(header([0]*len(vars_)))
    begins, off = [], hlen
    for v in vars_:
        if not v[4]: begins.append(off); off += pad(vsize(v))
        else: begins.append(None)
    recsize = 0
    for i, v in enumerate(vars_):
        if v[4]: begins[i] = off + recsize; recsize += pad(vsize(v))
    data = header(begins)
    data += b'xyz\0' + b'abc\0' + b'alpha' + b'beta\0' + b'gamma' + b'\0'
    data = data[:begins[3]] if len(data) > begins[3] else data + b'\0'*(begins[3]-len(data))
    for k in range(frames):
        data += struct.pack('>f', 1.5 * k)
        data += struct.pack(f'>{3*natoms}f', *[float(i) + 0.25*k for i in range(3*natoms)])
        data += struct.pack('>3d', 20.0, 21.0, 22.0) + struct.pack('>3d', 90.0, 90.0, 100.0)
    return data
out('netcdf','amber.nc', nc(4, 2))
out('netcdf','amber64.nc', nc(4, 2, cdf=2))

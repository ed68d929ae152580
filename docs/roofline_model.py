#!/usr/bin/env python3
"""The counts behind docs/performance.md, section "Roofline per stage".

Rebuilds, in numpy, the synthetic system of the paper's Table 1 row of 955,226 atoms at
H = 1 Å as `mdsurf bench --table1` builds it (src/gpu/table1.rs, src/synthetic.rs: the demo
rhodopsin tiled on a lattice with 2 Å gaps; R = 1, I = 0.5, quality medium, cutoff 2.5 alpha),
sizes it as src/gpu/plan.rs does (grid, bin cells, slabs, bricks, brick slots) and counts what
each GPU stage touches:

- reached bricks: the test of `mark` in shaders/bricks.wgsl, per atom;
- density: for randomly sampled threads of the sparse gather (`bricks` in
  shaders/density.wgsl, one thread per run of 8 samples along x), the atoms loaded from the
  bin cells around the run, those passing the y/z cutoff test and the sample-atom pairs within
  the cutoff; and for `bricks_tiled`, the atoms of the cells around each whole brick;
- Marching Cubes: the density on the whole grid (per-pair cutoff as in DESIGN section 2),
  then crossed edges (vertices), active cells, points owning vertices, non-empty blocks of
  256 classified points, and the samples emission reads.

Positions come from assets/md_1u19.gro (the benchmark reads frame 0 of the XTC and adds
0.1 Å of jitter), element radii from the first letter of the atom name. The grid it gives is
the benchmark's (303 x 317 x 425); its crossed edges come within 0.2 % of half the measured
triangle count. Bytes and operations are then formed as the document's formulas say.

Usage:  python/.venv/bin/python docs/roofline_model.py [--threads N] [--seed S]
        (numpy only; about half a minute and 1 GB of memory on one core)
"""

import argparse
import math
import os

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RADII = {"H": 1.0, "C": 1.5, "N": 1.4, "O": 1.3, "S": 1.9}
ATOMS, H, Q, ISO, BRICK, RUN = 955_226, 1.0, 2.5, 0.5, 8, 8
# H100 SXM limits assumed in the document.
HBM, FP32 = 3.35e12, 67e12
MEASURED = {"upload": 1.52, "bin": 0.20, "density": 8.49, "mc": 3.93, "frame": 15.4}
TRIANGLES = 6_963_260


def demo():
    lines = open(os.path.join(ROOT, "assets", "md_1u19.gro")).read().splitlines()
    n = int(lines[1])
    pos, rad = [], []
    for line in lines[2 : 2 + n]:
        pos.append([float(line[20:28]) * 10, float(line[28:36]) * 10, float(line[36:44]) * 10])
        rad.append(RADII[line[10:15].strip()[0]])
    return np.array(pos), np.array(rad)


def tiled(pos, rad, count):
    n = len(pos)
    lo, hi = pos.min(0), pos.max(0)
    stride = (hi - lo) + 2.0
    total = -(-count // n)
    nx = math.ceil(total ** (1 / 3))
    ny = max(1, math.ceil(math.sqrt(total / nx)))
    copies = []
    for c in range(total):
        cell = np.array([c % nx, (c // nx) % ny, c // (nx * ny)], dtype=float)
        copies.append(pos + stride * cell - lo)
    return np.concatenate(copies)[:count], np.tile(rad, total)[:count], total


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=60_000, help="density threads sampled")
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()

    P, R, copies = tiled(*demo(), ATOMS)
    N = len(P)
    max_cut = Q * R.max()
    pad = max_cut + H
    origin = P.min(0) - pad
    dims = (np.ceil((P.max(0) + pad - origin) / H) + 1).astype(int)
    cs = max(max_cut, H)
    cd = (np.floor((dims - 1) * H / cs) + 1).astype(int)
    M = int(cd.prod())
    print(f"atoms {N} ({copies} copies), grid {dims.tolist()} = {dims.prod():,} samples")
    print(f"bin cells {cs} Å, {cd.tolist()} = {M:,}")

    # Slabs (plan_frame with the H100's limits: 2^31 - 4 byte bindings, 1 GiB volume budget).
    layer = int(dims[0] * dims[1])
    fit = min((2_147_483_644) // (12 * layer), (4_292_870_144 // 4) // (32 * layer))
    own = int(dims[2]) if fit >= dims[2] else fit - 3
    slabs, z0 = [], 0
    while z0 < dims[2]:
        z1 = min(z0 + own, int(dims[2]))
        d0 = max(z0 - 1, 0)
        slabs.append((z0, z1, d0, min(z1 + 2, int(dims[2])) - d0))
        z0 = z1
    class_points = layer * min(own + 1, int(dims[2]))
    print(f"slabs (own z0, z1, density z0, layers) {slabs}; class points per slab {class_points:,}")

    # Reached bricks (bricks.wgsl mark).
    bd = -(-dims // BRICK)
    g = (P - origin) / H
    reach = (Q * R * 1.001 + 1e-3) / H
    flags = np.zeros(bd, dtype=bool)
    b0 = np.floor(g / BRICK).astype(int)
    for off in np.ndindex(3, 3, 3):
        b = b0 + np.array(off) - 1
        ok = np.all((b >= 0) & (b < bd), axis=1)
        d = np.maximum(np.maximum(b * BRICK - g, g - (b * BRICK + BRICK - 1)), 0)
        hit = ok & ((d**2).sum(1) < reach**2)
        flags[tuple(b[hit].T)] = True
    per_layer = flags.sum(axis=(0, 1))
    need = [per_layer[d0 // BRICK : (d0 + dl - 1) // BRICK + 1].sum() for _, _, d0, dl in slabs]
    slots = -(-(max(need) + max(need) // 8) // 64) * 64
    sparse_classes = slots * 729 < class_points
    print(f"bricks {bd.tolist()} = {bd.prod():,}, reached {flags.sum():,} "
          f"({100 * flags.sum() / bd.prod():.1f} %), slab needs {need}, slots {slots:,}, "
          f"class entries per {'brick slot' if sparse_classes else 'point'}")

    # Bin cells, sorted atoms (f32 as on the GPU).
    Pf, Rf, of = P.astype(np.float32), R.astype(np.float32), origin.astype(np.float32)
    csf = np.float32(cs)
    cc = np.clip(np.floor((Pf - of) / csf).astype(int), 0, cd - 1)
    lin = cc[:, 0] + cd[0] * (cc[:, 1] + cd[1] * cc[:, 2])
    order = np.argsort(lin, kind="stable")
    A, W, L = Pf[order], Rf[order], lin[order]
    start = np.searchsorted(L, np.arange(M), side="left")
    end = np.searchsorted(L, np.arange(M), side="right")
    rch = np.float32(max_cut) * np.float32(1.0001) + np.float32(1e-4)

    def cell(x, a):
        return int(min(max(math.floor((x - of[a]) / csf), 0), cd[a] - 1))

    # Density threads of the sparse gather: (i0, j, k) per reached brick in each slab.
    bricks = np.argwhere(flags)
    threads, dispatched, tiled_loads = [], 0, 0
    cnt = np.zeros(cd, int)
    np.add.at(cnt, tuple(cc.T), 1)
    pre = np.zeros(cd + 1, int)
    pre[1:, 1:, 1:] = cnt.cumsum(0).cumsum(1).cumsum(2)

    def box(x0, x1, y0, y1, z0, z1):
        return (pre[x1 + 1, y1 + 1, z1 + 1] - pre[x0, y1 + 1, z1 + 1] - pre[x1 + 1, y0, z1 + 1]
                - pre[x1 + 1, y1 + 1, z0] + pre[x0, y0, z1 + 1] + pre[x0, y1 + 1, z0]
                + pre[x1 + 1, y0, z0] - pre[x0, y0, z0])

    def cells(x, a):
        return np.clip(np.floor((x - of[a]) / csf).astype(int), 0, cd[a] - 1)

    for _, _, d0, dl in slabs:
        sel = bricks[(bricks[:, 2] >= d0 // BRICK) & (bricks[:, 2] <= (d0 + dl - 1) // BRICK)]
        dispatched += len(sel)
        lo = of + H * (sel * BRICK).astype(np.float32)
        hi = of + H * (sel * BRICK + BRICK - 1).astype(np.float32)
        tiled_loads += box(cells(lo[:, 0] - rch, 0), cells(hi[:, 0] + rch, 0),
                           cells(lo[:, 1] - rch, 1), cells(hi[:, 1] + rch, 1),
                           cells(lo[:, 2] - rch, 2), cells(hi[:, 2] + rch, 2)).sum()
        for ly in range(BRICK):
            for lz in range(BRICK):
                j, k = sel[:, 1] * BRICK + ly, sel[:, 2] * BRICK + lz
                ok = (j < dims[1]) & (k >= d0) & (k < d0 + dl)
                threads.append(np.stack([sel[ok, 0] * BRICK, j[ok], k[ok]], 1))
    threads = np.concatenate(threads)
    S = len(threads) * RUN
    rng = np.random.default_rng(args.seed)
    pick = threads[rng.choice(len(threads), min(args.threads, len(threads)), replace=False)]
    loads = passing = pairs = 0
    q = np.float32(Q)
    for i0, j, k in pick:
        xs = of[0] + np.float32(H) * np.arange(i0, i0 + RUN, dtype=np.float32)
        y, z = of[1] + np.float32(H * j), of[2] + np.float32(H * k)
        cx0, cx1 = cell(xs[0] - rch, 0), cell(xs[-1] + rch, 0)
        for cz in range(cell(z - rch, 2), cell(z + rch, 2) + 1):
            for cy in range(cell(y - rch, 1), cell(y + rch, 1) + 1):
                row = cd[0] * (cy + cd[1] * cz)
                a, b = start[row + cx0], end[row + cx1]
                if b <= a:
                    continue
                loads += b - a
                at, w = A[a:b], W[a:b]
                yz = (y - at[:, 1]) ** 2 + (z - at[:, 2]) ** 2
                cut2 = (q * w) ** 2
                p = yz < cut2
                passing += p.sum()
                if p.any():
                    d2 = (xs[None, :] - at[p, 0][:, None]) ** 2 + yz[p][:, None]
                    pairs += (d2 < cut2[p][:, None]).sum()
    f = len(threads) / len(pick)
    Lc, Yc, Cc = loads * f, passing * f, pairs * f
    print(f"density: {dispatched:,} brick dispatches, {len(threads):,} threads, {S:,} samples; "
          f"per thread {loads / len(pick):.1f} loads, {passing / len(pick):.1f} pass y/z, "
          f"{pairs / len(pick):.1f} pairs within the cutoff")
    print(f"  L = {Lc:.3g} loads, Y = {Yc:.3g} pass, 8Y = {8 * Yc:.3g} distance tests, "
          f"C = {Cc:.3g} pairs; tiled: {tiled_loads:.3g} loads, {64 * tiled_loads:.3g} y/z tests")

    # Density on the whole grid, then Marching Cubes counts.
    rho = np.zeros(dims, dtype=np.float32)
    for r in np.unique(R):
        idx = np.where(R == r)[0]
        c = Q * r
        offs = np.arange(-int(math.ceil(c)) - 1, int(math.ceil(c)) + 2)
        for s in range(0, len(idx), 20_000):
            p = P[idx[s : s + 20_000]]
            base = np.floor((p - origin) / H).astype(int)
            fr = (p - origin) / H - base
            for dz in offs:
                for dy in offs:
                    for dx in offs:
                        d2 = (dx - fr[:, 0]) ** 2 + (dy - fr[:, 1]) ** 2 + (dz - fr[:, 2]) ** 2
                        ok = d2 < c * c
                        if ok.any():
                            at = (base[ok, 0] + dx, base[ok, 1] + dy, base[ok, 2] + dz)
                            np.add.at(rho, at, np.exp(-d2[ok] / (2 * r * r)).astype(np.float32))
    inside = rho >= ISO
    del rho
    owner = np.zeros(dims, dtype=np.int8)
    ends = np.zeros(dims, dtype=bool)
    V = 0
    for ax in range(3):
        a = [slice(None)] * 3
        b = [slice(None)] * 3
        a[ax], b[ax] = slice(0, -1), slice(1, None)
        e = inside[tuple(a)] != inside[tuple(b)]
        V += int(e.sum())
        owner[tuple(a)] += e
        ends[tuple(a)] |= e
        ends[tuple(b)] |= e
    near = ends.copy()
    for ax in range(3):
        a = [slice(None)] * 3
        b = [slice(None)] * 3
        a[ax], b[ax] = slice(0, -1), slice(1, None)
        near[tuple(a)] |= ends[tuple(b)]
        near[tuple(b)] |= ends[tuple(a)]
    corners = np.zeros(dims - 1, dtype=np.int8)
    for c8 in range(8):
        x, y, z = c8 & 1, (c8 >> 1) & 1, (c8 >> 2) & 1
        corners += inside[x : dims[0] - 1 + x, y : dims[1] - 1 + y, z : dims[2] - 1 + z]
    active = owner > 0
    active[:-1, :-1, :-1] |= (corners > 0) & (corners < 8)
    Acells, owners = int(active.sum()), int((owner > 0).sum())
    flat = np.transpose(active, (2, 1, 0)).reshape(-1)
    nonempty = 0
    for z0, z1, _, _ in slabs:
        part = flat[z0 * layer : z1 * layer]
        blocks = -(-len(part) // 256)
        padded = np.zeros(blocks * 256, bool)
        padded[: len(part)] = part
        nonempty += int(padded.reshape(blocks, 256).any(1).sum())
    print(f"mesh: {V:,} crossed edges (T/2 = {TRIANGLES // 2:,}), {Acells:,} active cells, "
          f"{owners:,} points owning vertices, {nonempty:,} non-empty blocks of 256 points, "
          f"{int(ends.sum()):,} edge ends, {int(near.sum()):,} with their 6 neighbours")

    # Bytes and operations per stage (formulas of docs/performance.md).
    Vm, T = TRIANGLES / 2, TRIANGLES
    blocks = -(-class_points // 256)
    stages = {
        "bin": (108 * N + 36 * M, 20 * N),
        "density": (16 * S + 24 * N + 8 * M + 4 * (flags.sum() + bd.prod()),
                    8 * Lc + 43 * Yc + 10 * Cc),
        "mc": (4 * S + len(slabs) * (4 * class_points + 12 * blocks)   # classify
               + 6e6                                                   # scans
               + 4 * 256 * nonempty + 4 * owners + 8 * Acells + len(slabs) * 24 * blocks
               + 16 * Acells + 12 * int(ends.sum()) + 4 * int(near.sum()) + 36 * Vm + 12 * T
               + 12 * T + 36 * Vm,                                     # measure
               12 * layer * (dims[2] + len(slabs)) + 80 * Vm + 50 * T),
    }
    print(f"upload: {24 * N / 1e6:.1f} MB host traffic, {12 * N / 1e6:.1f} MB over PCIe")
    for name, (b, ops) in stages.items():
        tb, tf = b / HBM * 1e3, ops / FP32 * 1e3
        print(f"{name:8s} {b / 1e6:8.1f} MB  {tb:.3f} ms at HBM  {ops:.3g} ops  {tf:.4f} ms at FP32"
              f"  -> {100 * tb / MEASURED[name]:.1f} % / {100 * tf / MEASURED[name]:.2f} % of "
              f"{MEASURED[name]} ms")


if __name__ == "__main__":
    main()

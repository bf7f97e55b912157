#!/usr/bin/env python3
"""Halo model of colloidsim's DPD domain decomposition (docs/parallel.md).

Per step and rank: compute t_comp = (N/P) / r1 (the one-core rate; pairs are never computed
twice, the half stencil meets each once); ghost work t_ghost = s g / r1 (the ghost layer is
sorted and copied with the owned beads, a share s of a bead's cost, no forces); messages
t_msg = m_p2p alpha + m_coll alpha log2(P) + 80 g / B (a ghost travels as 7 numbers and its
halo force comes back as 3: 80 bytes). Efficiency E = t_comp / (t_comp + t_ghost + t_msg).

g (ghost beads per rank) is rho times the ghost volume:
- slabs (built): one layer of cells, width w, over the whole cross-section: g = rho Lx Ly w;
  at most nz = floor(Lz / w) ranks;
- a grid of py columns along y by pz slabs along z (built; the grid chosen as colloidsim
  chooses it, the fewest ghost cells per rank): the ghost layer over the column and its two
  fringe rows, g_z = rho Lx (Ly/py + 2w) w, and a fringe row of width w on each side of the
  column in every owned layer, g_y = 2 rho Lx w Lz/pz, whose pairs the rank computes too (a
  full bead's cost each, and 4 more messages a step);
- a 3D grid of cubic domains of edge l = L / P^(1/3) (not built): the half stencil needs the
  next cells along +x, +y, +z, their edges and corner: g = rho ((l + w)^3 - l^3).

Usage: python3 scripts/parallel_model.py [--r1 3.0e6] [--alpha 2e-6] [--bandwidth 1e10]
"""

import argparse
import math


def efficiency(n_per_rank, ghosts, p, a):
    if p == 1:
        return 1.0
    t_comp = n_per_rank / a.r1
    t_ghost = a.sort_share * ghosts / a.r1
    t_msg = a.p2p * a.alpha + a.collectives * a.alpha * math.log2(p) + 80.0 * ghosts / a.bandwidth
    return t_comp / (t_comp + t_ghost + t_msg)


def pencils(edge, p, a):
    """Efficiency of the y x z grid colloidsim chooses for a cube of `edge` on `p` ranks, and
    the grid, or None when no grid fits (as `Domain::choose_grid` and `Domain::grid`)."""
    nx = ny = nz = int(edge // a.w)
    best = None
    for py in range(1, p + 1):
        if p % py:
            continue
        pz = p // py
        if pz > nz or (py > 1 and (py > ny or math.ceil(ny / py) + 2 > ny)):
            continue
        slab = nx * (math.ceil(ny / py) + (2 if py > 1 else 0)) if pz > 1 else 0
        fringe = 2 * nx * math.ceil(nz / pz) if py > 1 else 0
        # A fringe cell costs four ghost-layer cells (its pairs are computed too).
        if best is None or slab + 4 * fringe < best[0]:
            best = (slab + 4 * fringe, py, pz)
    if best is None:
        return None
    _, py, pz = best
    if p == 1:
        return 1.0, py, pz
    n = a.rho * edge ** 3
    g_z = a.rho * edge * ((edge / py + 2 * a.w) if py > 1 else edge) * a.w if pz > 1 else 0.0
    g_y = 2 * a.rho * edge * a.w * edge / pz if py > 1 else 0.0
    t_comp = n / p / a.r1
    t_ghost = (a.sort_share * (g_z + g_y) + g_y) / a.r1
    m = a.p2p + (4 if py > 1 else 0)
    t_msg = m * a.alpha + a.collectives * a.alpha * math.log2(p) + 80.0 * (g_z + g_y) / a.bandwidth
    return t_comp / (t_comp + t_ghost + t_msg), py, pz


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--r1", type=float, default=3.0e6,
                    help="one-core rate, particle-steps/s (bench dpd, 1 rank 1 thread)")
    ap.add_argument("--rho", type=float, default=3.0, help="bead density")
    ap.add_argument("--w", type=float, default=1.0, help="cell width (rc at dt = 0.04)")
    ap.add_argument("--sort-share", type=float, default=0.1,
                    help="cost of sorting and copying a bead, as a share of its step")
    ap.add_argument("--alpha", type=float, default=2e-6, help="message latency, s")
    ap.add_argument("--bandwidth", type=float, default=1e10, help="bytes/s per rank")
    ap.add_argument("--p2p", type=int, default=8, help="point-to-point messages per step")
    ap.add_argument("--collectives", type=int, default=3, help="all-gathers per step")
    a = ap.parse_args()
    print(f"# r1 = {a.r1:.3g} particle-steps/s, rho = {a.rho}, w = {a.w}, sort share = "
          f"{a.sort_share}, alpha = {a.alpha:.1e} s, B = {a.bandwidth:.1e} B/s")

    print("\n## Weak scaling, slabs: a 30 x 30 x 30 box (81,000 beads) per rank, stacked along z")
    print("| ranks | box | E |")
    print("|---|---|---|")
    for p in [1, 2, 8, 64, 256, 1024]:
        g = a.rho * 30 * 30 * a.w
        print(f"| {p} | 30 x 30 x {30 * p} | {100 * efficiency(81000, g, p, a):.1f} % |")

    for edge in [30, 150]:
        n = a.rho * edge ** 3
        nz = int(edge // a.w)
        print(f"\n## Strong scaling of one cube L = {edge} ({n:,.0f} beads)")
        print("| ranks | slabs (built) | y x z grid (built): py x pz | 3D grid (not built) |")
        print("|---|---|---|---|")
        for p in [1, 2, 8, 30, 64, 150, 300, 1024, 4096]:
            slab = "n/a (more ranks than layers)"
            if p <= nz:
                g = a.rho * edge * edge * a.w
                slab = f"{100 * efficiency(n / p, g, p, a):.1f} %"
            l = edge / p ** (1.0 / 3.0)
            grid = "n/a (domain narrower than a cell)"
            if l >= a.w:
                g3 = a.rho * ((l + a.w) ** 3 - l ** 3)
                grid = f"{100 * efficiency(n / p, g3, p, a):.1f} %"
            pen = pencils(edge, p, a)
            pen = "n/a (no grid fits)" if pen is None else f"{100 * pen[0]:.1f} %: {pen[1]} x {pen[2]}"
            print(f"| {p} | {slab} | {pen} | {grid} |")


if __name__ == "__main__":
    main()

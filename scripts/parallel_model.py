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
        print("| ranks | slabs (built) | 3D grid (not built) |")
        print("|---|---|---|")
        for p in [1, 2, 8, 30, 64, 150, 1024]:
            slab = "n/a (more ranks than layers)"
            if p <= nz:
                g = a.rho * edge * edge * a.w
                slab = f"{100 * efficiency(n / p, g, p, a):.1f} %"
            l = edge / p ** (1.0 / 3.0)
            grid = "n/a (domain narrower than a cell)"
            if l >= a.w:
                g3 = a.rho * ((l + a.w) ** 3 - l ** 3)
                grid = f"{100 * efficiency(n / p, g3, p, a):.1f} %"
            print(f"| {p} | {slab} | {grid} |")


if __name__ == "__main__":
    main()

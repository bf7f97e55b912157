#!/bin/bash
# Interleaved A/B of engine speed between two colloidsim binaries, one thread: R rounds of five
# short engine benchmarks (BCD, WCA BD, DPD water, hard-sphere MC, MPCD solvent), the two
# binaries alternating within each round, so that the machine's load falls on both alike.
# Usage: scripts/bench_ab.sh OLD_BINARY NEW_BINARY [ROUNDS] > ab.txt; the tables follow
# "### round R old|new ENGINE" lines (docs/performance.md, "Engine speed across issue 41").
OLD=$1
NEW=$2
R=${3:-5}
for r in $(seq 1 "$R"); do
  for who in old new; do
    B=$OLD; [ "$who" = new ] && B=$NEW
    echo "### round $r $who bcd"; RAYON_NUM_THREADS=1 "$B" bench bcd --n 100000 --chronological 0 --repeats 1 --work 100000000 2>&1 | tail -3
    echo "### round $r $who bd"; "$B" bench bd --threads 1 --steps 2000 --repeats 1 --no-lammps 2>&1 | tail -4
    echo "### round $r $who dpd"; "$B" bench dpd --l 20 --threads 1 --steps 400 --warmup 50 --repeats 1 --skin 0.3 --no-lammps 2>&1 | tail -4
    echo "### round $r $who mc"; "$B" bench mc --n 10976 --phi 0.3 --threads 1 --nselect 1 --sweeps 300 --warmup 300 --repeats 1 2>&1 | tail -4
    echo "### round $r $who mpcd"; "$B" bench mpcd --l 30 --steps 100 --threads 1 --repeats 1 --no-lammps 2>&1 | tail -4
  done
done

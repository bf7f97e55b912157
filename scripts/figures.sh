#!/usr/bin/env bash
# Regenerate the papers' figures that finish in a few minutes on 2 cores (docs/figures.md):
#   bash scripts/figures.sh OUT [BINARY]
# OUT must not exist yet (nothing is overwritten); BINARY defaults to target/release/colloidsim
# (cargo build --release -p colloidsim-cli). Each figure gets its own folder OUT/<paper>-<figure>
# with the run's outputs and pictures; OUT/times.tsv lists the wall time of each.
set -euo pipefail
out=${1:?usage: bash scripts/figures.sh OUT [BINARY]}
bin=${2:-target/release/colloidsim}
here=$(cd "$(dirname "$0")/.." && pwd)
[ -x "$bin" ] && bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
[ -x "$bin" ] || { echo "no colloidsim binary at $bin: cargo build --release -p colloidsim-cli" >&2; exit 2; }
[ -e "$out" ] && { echo "$out exists; choose a new folder (nothing is overwritten)" >&2; exit 2; }
mkdir -p "$out"
printf 'figure\tcommand\tseconds\n' > "$out/times.tsv"

# figure name, then the colloidsim arguments (the output folder is appended as --out).
fig() {
    local name=$1; shift
    local start=$SECONDS
    echo "== $name: colloidsim $*" >&2
    "$bin" "$@" --out "$out/$name" --quiet
    printf '%s\tcolloidsim %s\t%d\n' "$name" "$*" $((SECONDS - start)) >> "$out/times.tsv"
}

# A DDFT of a droplet scenario (`colloidsim theory`, which has no --quiet).
theory() {
    local name=$1; shift
    local start=$SECONDS
    echo "== $name: colloidsim theory $*" >&2
    "$bin" theory "$@" --out "$out/$name" >/dev/null
    printf '%s\tcolloidsim theory %s\t%d\n' "$name" "$*" $((SECONDS - start)) >> "$out/times.tsv"
}

# A droplet run and its DDFT, which draws the run's profiles beside its own when the run's
# folder (the scenario's stem) is in the working directory: both go into OUT/<name>/.
run_and_theory() {
    local name=$1 scenario=$2
    local start=$SECONDS
    echo "== $name: colloidsim run and theory $scenario" >&2
    mkdir -p "$out/$name"
    (cd "$out/$name" && "$bin" run "$scenario" --quiet && "$bin" theory "$scenario" >/dev/null)
    printf '%s\tcolloidsim run + theory %s\t%d\n' "$name" "$scenario" $((SECONDS - start)) >> "$out/times.tsv"
}

ex=$here/examples
# Hard-rods paper.
fig hard-rods-fig3 run "$ex/bcd/hard-rods-cosine.toml"
fig hard-rods-fig4 ensemble "$ex/bcd/contact-density.toml" --replicas 8
fig hard-rods-fig6 run "$ex/bcd/sticky-rods.toml"
fig hard-rods-fig7-gamma0 run "$ex/bcd/single-file.toml"
fig hard-rods-fig7-gamma1 run "$ex/bcd/sticky-single-file.toml"
# Drying-droplet paper.
fig droplet-fig2a-phi0.2 run "$ex/droplet/static-equilibrium.toml"
run_and_theory droplet-fig2b "$ex/droplet/drying-bd.toml"
fig droplet-figS4 run "$ex/droplet/drying-mpcd-solvent.toml"
theory droplet-figS10 "$ex/droplet/drying-bd-paper.toml" --dx 0.02
fig droplet-fig7 run "$ex/mc/droplet-static.toml"

echo "== done; wall times in $out/times.tsv" >&2
column -t -s $'\t' "$out/times.tsv" >&2 || cat "$out/times.tsv" >&2

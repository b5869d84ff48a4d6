#!/usr/bin/env bash
# The power analysis on this machine (docs/BENCHMARKS.md, "Power analysis"):
#   1. the paper's design (10 subjects, 11 + 11 trials), 4 replicates, on one process with one
#      thread, then on two MPI ranks of one thread each (mpirun -n 2) in the same run: studies
#      per second and the ratio; and one process with two threads (subjects at once);
#   2. one replicate of the default table's largest design (40 subjects) on two ranks, from
#      which the default table (designs 6, 10, 20, 40; 200 replicates) is projected: a replicate
#      runs only its largest design (the smaller ones analyze its first subjects).
# Usage: bench/power_scaling.sh [--quick] [BUILD_DIR]   (default build/release). --quick: the
# smoke size the doc test runs (4 subjects, 2 replicates, 2 + 2 trials; 6 subjects for the
# largest design): it proves the script and mpirun work; its figures mean nothing.
set -euo pipefail
design="--subjects 10 --replicates 4 --trials 11"
largest="--subjects 40 --replicates 2 --trials 11"
folders=()
for arg in "$@"; do
  if [[ "$arg" == "--quick" ]]; then
    design="--subjects 4 --replicates 2 --trials 2"
    largest="--subjects 6 --replicates 2 --trials 2"
  else
    folders+=("$arg")
  fi
done
build=$(realpath "${folders[0]:-build/release}")
hattr="$build/apps/hattr/hattr"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # these machines run as root
rate() { python3 -c 'import json,sys; r=json.load(sys.stdin)["run"]; print("%d studies in %.1f s: %.4f studies/s" % (r["studies"], r["seconds"], r["studies_per_second"]))'; }

# This run's own folder for the two tables (two runs at once must not share files).
work=$(mktemp -d /tmp/hattr-power-scaling-XXXXXX)
trap 'rm -rf "$work"' EXIT
echo "== the paper's design ($design)"
one=$("$hattr" sim power $design --threads 1 --json | tee "$work/power-one.json" | rate)
echo "1 process, 1 thread:   $one"
two=$(mpirun -n 2 "$hattr" sim power $design --threads 1 --json | tee "$work/power-two.json" | rate)
echo "2 processes (mpirun):  $two"
threads=$("$hattr" sim power $design --threads 2 --json | rate)
echo "1 process, 2 threads:  $threads"
python3 - "$work" <<'PY'
import json, sys
one, two = (json.load(open(f"{sys.argv[1]}/power-{k}.json")) for k in ("one", "two"))
same = one["rows"] == two["rows"]
print(f"2 processes / 1: {two['run']['studies_per_second'] / one['run']['studies_per_second']:.2f}x; tables the same: {same}")
PY

echo "== the largest default design (40 subjects; 6 with --quick), 2 replicates on 2 ranks"
big=$(mpirun -n 2 "$hattr" sim power $largest --threads 1 --json | rate)
echo "$largest, 2 processes: $big"

#!/usr/bin/env bash
# Stations on one PostgreSQL server, measured on this machine (docs/BENCHMARKS.md, "Many
# stations"): a throwaway server (initdb + pg_ctl in a temporary folder, Unix socket only,
# durable: fsync on, as a lab's server), then
#   1. storing and reading a 4.5 s trial on it, against SQLite in the same run (bench_study_store);
#   2. one 30-subject study of the paper's protocol (1 980 trials of the simulated expert's 'Na')
#      run by 1, 2 and 3 stations at once (`hattr study run`), and the same study by one
#      station on SQLite: wall time, trials per second, and the stores' sizes.
# Usage: bench/study_stations.sh [--quick] [BUILD_DIR]   (default build/release). As root, the
# server runs as the `postgres` user (PostgreSQL refuses root). --quick: the smoke size the doc
# test runs (bench_study_store --quick; 2 subjects, 132 trials, by 1 and 2 stations, and an 8 s
# lease so that an idle station asks again after 2 s, not 7.5): it proves the script works; its
# figures mean nothing.
set -euo pipefail
subjects=30
station_counts=(1 2 3)
lease=()
store_size=()
folders=()
for arg in "$@"; do
  if [[ "$arg" == "--quick" ]]; then
    subjects=2
    station_counts=(1 2)
    lease=(--lease-timeout 8)
    store_size=(--quick)
  else
    folders+=("$arg")
  fi
done
trials=$(( subjects * 66 ))
build=$(realpath "${folders[0]:-build/release}")
hattr="$build/apps/hattr/hattr"
bin=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -1)
as=()
dir=$(mktemp -d /tmp/hattr-pgbench-XXXXXX)
if (( EUID == 0 )); then
  as=(runuser -u postgres --)
  chown postgres "$dir"
fi
stop() {
  "${as[@]}" "$bin/pg_ctl" -D "$dir/data" -m fast stop >/dev/null 2>&1 || true
  rm -rf "$dir"
}
trap stop EXIT
"${as[@]}" "$bin/initdb" -D "$dir/data" --auth=trust --username=postgres --no-instructions >/dev/null
"${as[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -o "-k $dir -c listen_addresses=''" start >/dev/null
address() { echo "postgresql:///$1?host=$dir&user=postgres"; }
createdb() { (cd / && "${as[@]}" "$bin/createdb" -h "$dir" -U postgres "$1"); }
size_mb() { cd / && "${as[@]}" "$bin/psql" -h "$dir" -U postgres -d "$1" -Atc "SELECT round(pg_database_size('$1') / 1e6, 1)"; }

echo "== storing and reading a trial (SQLite, then PostgreSQL)"
createdb bench_store
createdb bench_read
HATTR_BENCH_PG_STORE=$(address bench_store) HATTR_BENCH_PG_READ=$(address bench_read) \
  "$build/bench/bench_study_store" "${store_size[@]}" --benchmark_format=console 2>&1 | grep -E "_(mean|median|stddev) "

echo "== one $subjects-subject study by ${station_counts[*]} stations"
work=$(mktemp -d /tmp/hattr-stations-XXXXXX)
cd "$work"
"$hattr" sim expert --glyph na -o expert.csv >/dev/null
"$hattr" study example | python3 -c 'import json,sys; s=json.load(sys.stdin); s["subjects"]["count"]='"$subjects"'; s["protocol"]["rest_s"]=0; print(json.dumps(s))' > study.json
"$hattr" study init study.json --db one.sqlite >/dev/null
start=$(date +%s.%N)
"$hattr" study run --quiet --db one.sqlite >/dev/null
end=$(date +%s.%N)
python3 -c "t=$end-$start; print(f'sqlite, 1 station: {t:.1f} s, {$trials/t:.1f} trials/s, file {__import__(\"os\").path.getsize(\"one.sqlite\")/1e6:.1f} MB')"
for stations in "${station_counts[@]}"; do
  db="stations_$stations"
  createdb "$db"
  "$hattr" study init study.json --db "$(address "$db")" >/dev/null
  start=$(date +%s.%N)
  pids=()
  for ((s = 0; s < stations; ++s)); do
    "$hattr" study run --quiet "${lease[@]}" --db "$(address "$db")" >/dev/null &
    pids+=($!)
  done
  for pid in "${pids[@]}"; do wait "$pid"; done
  end=$(date +%s.%N)
  python3 -c "t=$end-$start; print(f'postgresql, $stations station(s): {t:.1f} s, {$trials/t:.1f} trials/s, database $(size_mb "$db") MB')"
done
cd / && rm -rf "$work"

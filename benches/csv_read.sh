#!/usr/bin/env bash
# CSV reading speed: the reader alone (examples/read_file: `read_dataset_columns` as `fit`
# reads a file, timed in-process) on the 1M-row hemisphere file of benches/big_fit.sh
# (generated into $BIG_DIR, default /tmp/goniofit-big), in MB/s of the file's size.
# With BASE=path/to/read_file (the example built from another tree) the baseline runs too,
# alternated run by run; medians and the ratio are printed.
#
# Usage: [BASE=...] [NEW=...] bash benches/csv_read.sh [repeats]
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-5}
target=${CARGO_TARGET_DIR:-$PWD/target}
if [ -z "${NEW:-}" ]; then
  cargo build --release --quiet --example read_file
  NEW=$target/release/examples/read_file
fi
dir=${BIG_DIR:-/tmp/goniofit-big}
data=$dir/hemi-1000000.csv
if [ ! -s "$data" ]; then
  cargo build --release --quiet
  mkdir -p "$dir"
  "$target/release/goniofit" synth --model kbs --params sigma=0.25,T=2.5,scale=1 --wavelength 1 \
    --layout hemisphere --grid 10x100x1000 --noise 0.01 --seed 1 --out "$data" 2>/dev/null
fi
bins=("new=$NEW")
[ -n "${BASE:-}" ] && bins=("base=$BASE" "${bins[@]}")
python3 - "$data" "$repeats" "${bins[@]}" <<'PY'
import re, statistics, subprocess, sys
data, repeats = sys.argv[1], int(sys.argv[2])
bins = [b.split("=", 1) for b in sys.argv[3:]]
res = {name: [] for name, _ in bins}
for _ in range(repeats):
    for name, binary in bins:
        out = subprocess.run([binary, data], capture_output=True, text=True, check=True).stdout
        res[name].append(float(re.search(r"\(([\d.]+) MB/s\)", out).group(1)))
print(f"{data}: reader alone, {repeats} runs each (alternated)")
for name, _ in bins:
    runs = ", ".join(f"{x:.0f}" for x in res[name])
    print(f"  {name:4}  {statistics.median(res[name]):6.1f} MB/s (runs {runs})")
if len(bins) == 2:
    print(f"  new/base: {statistics.median(res['new']) / statistics.median(res['base']):.2f}x")
PY

#!/bin/sh
# Time and peak memory of reading a full-size MERL file (33 MB: 90 × 90 × 180 cells × 3
# channels of f64), one channel and all three, with /usr/bin/time -v. The file is written
# here by a few lines of Python (a smooth made-up BRDF; every 50th cell unmeasured).
# Usage: benches/merl_read.sh   (builds the example read_file in release mode)
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 - "$dir/bench.binary" <<'PY'
import math, struct, sys
n = 90 * 90 * 180
with open(sys.argv[1], "wb") as f:
    f.write(struct.pack("<3i", 90, 90, 180))
    for c in range(3):
        row = [(-1.0 if k % 50 == 0 else 150.0 * (1 + c) * (1.0 + math.cos(k * 1e-3))) for k in range(n)]
        f.write(struct.pack("<%dd" % n, *row))
PY
(cd "$root" && cargo build --release --example read_file >/dev/null 2>&1)
bin="$root/target/release/examples/read_file"
ls -l "$dir/bench.binary"
for channel in r all; do
    echo "== channel $channel"
    /usr/bin/time -v "$bin" "$dir/bench.binary" "$channel" 2>&1 |
        grep -E "samples|Elapsed \(wall|Maximum resident"
done

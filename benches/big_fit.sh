#!/usr/bin/env bash
# Time and peak memory of one big fit: a KBS hemisphere scan of ROWS rows
# (σ = 0.25 λ, T = 2.5 λ, 1 % noise, `goniofit synth`, seed 1) fitted with
# `goniofit fit --model kbs --wavelength 1 --json`, measured with `/usr/bin/time -v`
# (wall time, peak resident set size, bytes per row = peak RSS / rows), and the time outside
# the fit: wall minus the report's `seconds` (the fit: start, solve, uncertainty, fitted
# values and adequacy tests) and `interval_seconds` (the profile intervals), i.e. starting
# the process, reading the file, preparing the samples and writing the report. FIT_ARGS
# adds options to the fit (e.g. FIT_ARGS=--no-intervals).
#
# With BASE=path/to/goniofit the baseline binary runs too, alternated run by run with this
# tree's binary; medians and ratios are printed. Data files go to $BIG_DIR (default
# /tmp/goniofit-big), never into the repository; a 10M-row file is ~450 MB.
#
# Usage: [BASE=/tmp/goniofit-base] [NEW=...] [FIT_ARGS=...] bash benches/big_fit.sh [repeats] [rows: 1000000 | 10000000]
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-3}
rows=${2:-1000000}
# NEW=path measures another binary instead of building this tree's.
if [ -z "${NEW:-}" ]; then
  cargo build --release --quiet
  NEW=$PWD/target/release/goniofit
fi
dir=${BIG_DIR:-/tmp/goniofit-big}
mkdir -p "$dir"
case $rows in
  1000000) grid=10x100x1000 ;;
  10000000) grid=10x250x4000 ;;
  *) echo "rows must be 1000000 or 10000000" >&2; exit 2 ;;
esac
data=$dir/hemi-$rows.csv
if [ ! -s "$data" ]; then
  "$NEW" synth --model kbs --params sigma=0.25,T=2.5,scale=1 --wavelength 1 --layout hemisphere \
    --grid "$grid" --noise 0.01 --seed 1 --out "$data" 2>/dev/null
fi
bins=("new=$NEW")
[ -n "${BASE:-}" ] && bins=("base=$BASE" "${bins[@]}")
python3 - "$data" "$rows" "$repeats" "${FIT_ARGS:-}" "${bins[@]}" <<'PY'
import json, re, statistics, subprocess, sys
data, rows, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
extra = sys.argv[4].split()
bins = [b.split("=", 1) for b in sys.argv[5:]]
def run(binary):
    p = subprocess.run(["/usr/bin/time", "-v", binary, "fit", "--model", "kbs", "--wavelength", "1",
                        "--json", *extra, data], capture_output=True, text=True)
    d = json.loads(p.stdout)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1)) * 1024
    m = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (?:(\d+):)?(\d+):([\d.]+)", p.stderr)
    wall = int(m.group(1) or 0) * 3600 + int(m.group(2)) * 60 + float(m.group(3))
    return {"wall": wall, "fit_s": d["seconds"], "int_s": d.get("interval_seconds", 0.0), "rss": rss, "sigma": d["params"]["sigma"]["value"],
            "T": d["params"]["T"]["value"], "converged": d["converged"], "cost": d["cost"]}
res = {name: [] for name, _ in bins}
for _ in range(repeats):
    for name, binary in bins:
        res[name].append(run(binary))
print(f"{rows} rows ({data}), {repeats} runs each (alternated)")
med = {}
for name, _ in bins:
    rs = res[name]
    m = {k: statistics.median(r[k] for r in rs) for k in ("wall", "fit_s", "int_s", "rss")}
    med[name] = m
    r = rs[-1]
    runs = ", ".join("%.2f s/%.0f" % (x["wall"], x["rss"] / rows) for x in rs)
    outside = statistics.median(r['wall'] - r['fit_s'] - r['int_s'] for r in rs)
    print(f"  {name:4}  wall {m['wall']:6.2f} s (fit {m['fit_s']:.2f} s, intervals {m['int_s']:.2f} s, "
          f"outside them {outside:.2f} s)  peak RSS {m['rss'] / 2**20:7.1f} MiB"
          f" = {m['rss'] / rows:6.1f} bytes/row  (runs: {runs})"
          f"  sigma {r['sigma']:.6f} T {r['T']:.5f} converged {r['converged']} cost {r['cost']:.9e}")
if "base" in med:
    b, w = med["base"], med["new"]
    print(f"  new/base: wall {w['wall'] / b['wall']:.2f}, peak memory {w['rss'] / b['rss']:.2f}")
PY

#!/usr/bin/env bash
# The whole process of a texel batch with its summary as the output: `goniofit fit
# --by-group --model kbs --wavelength 1 --quiet --threads 2 [ARGS]` on the batch of
# benches/texels.py (2,000 in-plane KBS scans of 66 samples by default), wall time from
# outside (reading, fitting, writing the outputs) and fits per second, with the recovery
# of every texel's T/σ (within 5 % of the truth) read from the summary rows: the standard
# output when ARGS hold `--summary -`, else a `--summary` file (the text reports then go
# to /dev/null). Peak memory is the process's maximum resident set (`/usr/bin/time`).
#
# NEW_ARGS are this tree's binary's arguments (default `--warm-start --summary -`); with
# BASE=path/to/goniofit a baseline binary runs too with BASE_ARGS (default none: text
# reports and a summary file), alternated run by run; medians and the ratio are printed.
#
# Usage: [BASE=...] [NEW=...] [NEW_ARGS=...] [BASE_ARGS=...] bash benches/texels_process.sh [repeats] [texels]
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-7}
texels=${2:-2000}
source benches/texel_batch.sh
bins=("new=$NEW=${NEW_ARGS---warm-start --summary -}")
[ -n "${BASE:-}" ] && bins=("base=$BASE=${BASE_ARGS:-}" "${bins[@]}")
python3 - "$data" "$repeats" "${bins[@]}" <<'PY'
import csv, io, statistics, subprocess, sys, tempfile, time
data, repeats = sys.argv[1], int(sys.argv[2])
bins = [b.split("=", 2) for b in sys.argv[3:]]
truth = {r["group"]: float(r["T"]) / float(r["sigma"])
         for r in csv.DictReader(open(data[:-4] + ".truth.csv"))}
def run(binary, extra):
    args = [binary, "fit", "--by-group", "--model", "kbs", "--wavelength", "1", "--quiet",
            "--threads", "2", *extra.split()]
    with tempfile.NamedTemporaryFile("w+", suffix=".csv") as f, \
            tempfile.NamedTemporaryFile("w+", suffix=".rss") as m:
        to_file = "--summary" not in extra.split()
        if to_file:
            args += ["--summary", f.name]
        t = time.perf_counter()
        p = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", m.name] + args + [data],
                           capture_output=not to_file, text=True,
                           stdout=subprocess.DEVNULL if to_file else None)
        wall = time.perf_counter() - t
        text = open(f.name).read() if to_file else p.stdout
        rss = int(open(m.name).read().split()[-1]) / 1024
    rows = list(csv.DictReader(io.StringIO(text)))
    within = sum(abs(float(r["T_over_sigma"]) / truth[r["group"].rsplit("[", 1)[-1][:-1]] - 1) <= 0.05
                 for r in rows)
    conv = sum(r["converged"] == "true" for r in rows)
    return wall, len(rows), within, conv, rss
res = {name: [] for name, _, _ in bins}
for _ in range(repeats):
    for name, binary, extra in bins:
        res[name].append(run(binary, extra))
print(f"{data}: whole process, --threads 2, {repeats} runs each (alternated)")
for name, _, extra in bins:
    walls = [r[0] for r in res[name]]
    n, within, conv = res[name][-1][1:4]
    m = statistics.median(walls)
    rss = statistics.median(r[4] for r in res[name])
    print(f"  {name:4} {extra or '(default)':26} {m:.3f} s = {n / m:6.0f} fits/s (runs "
          + ", ".join(f"{w:.3f}" for w in walls)
          + f"); peak RSS {rss:.0f} MiB; T/sigma within 5 %: {within}/{n}, converged {conv}")
if len(bins) == 2:
    b, w = (statistics.median(r[0] for r in res[k]) for k in ("base", "new"))
    per = ", ".join(f"{x[0] / y[0]:.2f}" for x, y in zip(res["base"], res["new"]))
    print(f"  new/base speed-up: {b / w:.2f}x (per pair {per})")
PY

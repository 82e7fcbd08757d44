#!/usr/bin/env bash
# Where the time of a small fit goes: the texel batch of benches/texels.py (2,000 in-plane
# KBS scans of 66 samples, one CSV with a `group` column), fitted with `goniofit fit
# --by-group --model kbs --wavelength 1 --json` and GONIOFIT_STAGES=1, which makes the
# command write one JSON line of stage times on standard error (src/commands/stages.rs).
#
# Per run: the process's phases (reading the file, the batch of fits, reports and
# outputs: wall seconds) and the median over the batch of each stage of one fit (start
# grid, refinement, solve, uncertainty, assembling the report's figures, intervals, the
# whole dataset's fit: µs of wall time on the thread that ran it). Printed: the median of
# each figure over the runs. With BASE=path/to/goniofit a baseline binary runs too,
# alternated run by run; a binary without the stage line is timed from its JSON report
# (grid = start_seconds, refinement = init_seconds − start_seconds, the rest of the fit =
# seconds − init_seconds), and the process from outside (wall).
#
# Usage: [BASE=...] [NEW=...] [THREADS=2] bash benches/stages.sh [repeats] [texels]
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-5}
texels=${2:-2000}
source benches/texel_batch.sh
bins=("new=$NEW")
[ -n "${BASE:-}" ] && bins=("base=$BASE" "${bins[@]}")
python3 - "$data" "$repeats" "${THREADS:-2}" "${bins[@]}" <<'PY'
import json, os, statistics, subprocess, sys, tempfile, time
data, repeats, threads = sys.argv[1], int(sys.argv[2]), sys.argv[3]
bins = [b.split("=", 1) for b in sys.argv[4:]]
STAGES = ["grid", "refine", "solve", "uncertainty", "assemble", "intervals", "dataset"]
def run(binary):
    env = dict(os.environ, GONIOFIT_STAGES="1")
    with tempfile.NamedTemporaryFile("w+", suffix=".json") as out:
        t = time.perf_counter()
        p = subprocess.run([binary, "fit", "--by-group", "--model", "kbs", "--wavelength", "1",
                            "--json", "--quiet", "--threads", threads, data],
                           stdout=out, stderr=subprocess.PIPE, text=True, env=env)
        wall = time.perf_counter() - t
        d = json.load(open(out.name))
    lines = [l for l in p.stderr.splitlines() if l.startswith("{")]
    r = {"wall": wall, "fit_s": d["seconds"], "fits": len(d["fits"])}
    if lines:
        s = json.loads(lines[-1])
        r.update({k: s[k] for k in ("read_s", "report_s")})
        r.update(s["median_us"])
    else:
        med = lambda f: 1e6 * statistics.median(f(x) for x in d["fits"])
        r["grid"] = med(lambda x: x["start_seconds"])
        r["refine"] = med(lambda x: x["init_seconds"] - x["start_seconds"])
        r["rest of the fit"] = med(lambda x: x["seconds"] - x["init_seconds"])
    return r
res = {name: [] for name, _ in bins}
for _ in range(repeats):
    for name, binary in bins:
        res[name].append(run(binary))
print(f"{data}: {repeats} runs each (alternated), --threads {threads}, medians over the runs")
for name, _ in bins:
    rs = res[name]
    keys = [k for k in rs[0] if k not in ("fits",)]
    m = {k: statistics.median(r[k] for r in rs) for k in keys}
    n = rs[0]["fits"]
    print(f"  {name:4}  process {m['wall']:.3f} s ({n / m['wall']:.0f} fits/s), fits "
          f"{m['fit_s']:.3f} s ({n / m['fit_s']:.0f} fits/s)"
          + (f", reading {m['read_s']:.3f} s, reports {m['report_s']:.3f} s" if "read_s" in m else ""))
    per = ", ".join(f"{k} {m[k]:.1f}" for k in STAGES + ["rest of the fit"] if k in m)
    print(f"        per fit (median µs): {per}")
if len(bins) == 2:
    b, w = (statistics.median(r["wall"] for r in res[k]) for k in ("base", "new"))
    bf, wf = (statistics.median(r["fit_s"] for r in res[k]) for k in ("base", "new"))
    print(f"  new/base speed-up: process {b / w:.2f}x, fits {bf / wf:.2f}x")
PY

#!/usr/bin/env bash
# Throughput of many small fits: the texel batch of benches/texels.py (2,000
# in-plane KBS scans of 66 samples in one CSV with a `group` column, 1 % noise, seeded),
# fitted with `goniofit fit --by-group --model kbs --wavelength 1 --json`.
#
# Per run it records the batch's fit time (the report's `seconds`: from the first fit's
# start to the last fit's end, reading excluded), the whole process (wall, user + system CPU,
# peak RSS via /usr/bin/time), and the recovery of every texel (T/σ within 5 % of the truth,
# verdict counts, benches/texels.py check). With BASE=path/to/goniofit the baseline binary
# runs too, alternated run by run with this tree's binary so that both see the same machine
# state; medians and the ratio are printed. THREADS="1 2" (default) repeats everything per
# thread count (`--threads`, the fit's own pool; RAYON_NUM_THREADS alone does not set it),
# for the 1 → 2 thread scaling.
#
# The batch is generated once into $TEXELS_DIR (default /tmp/goniofit-texels), never into
# the repository.
#
# Usage: [BASE=/tmp/goniofit-base] [NEW=...] [THREADS="1 2"] bash benches/texels.sh [repeats] [texels]
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-5}
texels=${2:-2000}
threads=${THREADS:-1 2}
source benches/texel_batch.sh
truth=${data%.csv}.truth.csv
bins=("new=$NEW")
[ -n "${BASE:-}" ] && bins=("base=$BASE" "${bins[@]}")
python3 - "$data" "$truth" "$repeats" "$threads" "${bins[@]}" <<'PY'
import json, os, statistics, subprocess, sys, tempfile
data, truth, repeats, threads = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4].split()
bins = [b.split("=", 1) for b in sys.argv[5:]]
def run(binary, nthreads):
    env = dict(os.environ, RAYON_NUM_THREADS=nthreads)
    with tempfile.NamedTemporaryFile("w+", suffix=".json") as out, \
         tempfile.NamedTemporaryFile("w+") as tm:
        subprocess.run(["/usr/bin/time", "-f", "%e %U %S %M", "-o", tm.name, binary, "fit",
                        "--by-group", "--model", "kbs", "--wavelength", "1", "--json",
                        "--threads", nthreads, data],
                       stdout=out, stderr=subprocess.DEVNULL, env=env)
        wall, user, sys_, rss = open(tm.name).read().split()[-4:]
        d = json.load(open(out.name))
        check = json.loads(subprocess.run([sys.executable, "benches/texels.py", "check", "--truth",
                                           truth, out.name], capture_output=True, text=True,
                                          check=True).stdout)
    return {"fit_s": d["seconds"], "wall": float(wall), "cpu": float(user) + float(sys_),
            "rss_mb": int(rss) / 1024, "check": check}
for nt in threads:
    res = {name: [] for name, _ in bins}
    for _ in range(repeats):
        for name, binary in bins:
            res[name].append(run(binary, nt))
    print(f"threads {nt}, {repeats} runs each (alternated)")
    med = {}
    for name, _ in bins:
        rs = res[name]
        n = rs[0]["check"]["fits"]
        m = {k: statistics.median(r[k] for r in rs) for k in ("fit_s", "wall", "cpu", "rss_mb")}
        med[name] = m
        c = rs[-1]["check"]
        runs = ", ".join("%.0f" % (n / r["fit_s"]) for r in rs)
        print(f"  {name:4}  fits/s {n / m['fit_s']:8.0f} (fit stage {m['fit_s']:.3f} s; runs "
              f"{runs})  process wall {m['wall']:.2f} s"
              f"  cpu {m['cpu']:.2f} s ({n / m['cpu']:.0f} fits per cpu-s)  peak {m['rss_mb']:.0f} MB")
        print(f"        recovery: {c['T_over_sigma_within_5pct']}/{n} T/sigma within 5 % (worst "
              f"{100 * c['worst_T_over_sigma_rel_error']:.2f} %), converged {c['converged']}, "
              f"verdicts {c['verdicts']}")
    if "base" in med:
        b, w = med["base"], med["new"]
        ratios = ", ".join("%.2f" % (x["fit_s"] / y["fit_s"]) for x, y in zip(res["base"], res["new"]))
        print(f"  new/base speed-up: fit stage {b['fit_s'] / w['fit_s']:.2f}x (per-pair "
              f"{ratios}), process wall {b['wall'] / w['wall']:.2f}x,"
              f" cpu {b['cpu'] / w['cpu']:.2f}x")
PY

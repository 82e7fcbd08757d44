#!/usr/bin/env bash
# Cost of the profile-likelihood intervals on every channel of the Cornell
# paints: `fit --model kbs+lambert --quantity brdf --residual log --threads 1 --json
# --channel C`, one process per channel, with intervals and with --no-intervals. With
# BASE=path/to/old/goniofit the baseline binary runs too, alternated channel by channel
# with this tree's binary so that both see the same machine state.
#
# Per run it records the process's user + system CPU (/usr/bin/time), and from this tree's
# JSON the fit's `seconds` and the intervals' `interval_seconds` (wall, in the process).
# Printed: medians over the channels, and the ratio of the medians against the baseline.
# The interval widths of both binaries are compared too (largest relative difference of
# an end against the interval's half-width), so that a faster search that moved an end
# shows.
#
# Usage: [BASE=/tmp/goniofit-base] [NEW=...] bash benches/intervals.sh [paint.astm ...]
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${NEW:-}" ]; then
  cargo build --release --quiet
  NEW=$PWD/target/release/goniofit
fi
files=("$@")
[ ${#files[@]} -eq 0 ] && files=(data/cornell/garnet_red.astm data/cornell/krylon_blue.astm)
python3 - "$NEW" "${BASE:-}" "${files[@]}" <<'PY'
import json, statistics, subprocess, sys, tempfile, os
new, base, files = sys.argv[1], sys.argv[2], sys.argv[3:]
def channels(path):
    for line in open(path, errors="replace"):
        if line.startswith("VARS"):
            return [c for c in line.split(None, 1)[1].strip().split(",") if c.endswith("nm")]
    return []
def run(binary, path, ch, extra):
    with tempfile.NamedTemporaryFile(suffix=".time") as tf:
        cmd = ["/usr/bin/time", "-f", "%U %S", "-o", tf.name, binary, "fit", "--model",
               "kbs+lambert", "--quantity", "brdf", "--residual", "log", "--threads", "1",
               "--json", "--quiet", "--channel", ch, path] + extra
        out = subprocess.run(cmd, capture_output=True, text=True)
        u, s = open(tf.name).read().split()[-2:]
    return float(u) + float(s), json.loads(out.stdout)
def ends(v):
    out = {}
    for sec in ("params", "derived"):
        for name, p in v.get(sec, {}).items():
            for key in ("interval68", "interval95"):
                if isinstance(p, dict) and key in p:
                    out[(name, key)] = (p["value"], p[key])
    return out
rows = []
for path in files:
    for ch in channels(path):
        r = {"ch": os.path.basename(path) + ":" + ch}
        r["cpu_new"], v = run(new, path, ch, [])
        r["fit_s"], r["iv_s"] = v["seconds"], v.get("interval_seconds", float("nan"))
        r["cpu_none"], _ = run(new, path, ch, ["--no-intervals"])
        if base:
            r["cpu_base"], vb = run(base, path, ch, [])
            worst = 0.0
            a, b = ends(v), ends(vb)
            for k in a.keys() & b.keys():
                val, ia = a[k]
                ib = b[k][1]
                for lo_hi in (0, 1):
                    x, y = ia[lo_hi], ib[lo_hi]
                    if x is None or y is None:
                        if (x is None) != (y is None):
                            worst = float("inf")
                        continue
                    half = abs(y - val) or 1.0
                    worst = max(worst, abs(x - y) / half)
            r["end_diff"] = worst
        rows.append(r)
        print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in r.items()), flush=True)
med = lambda k: statistics.median(r[k] for r in rows)
print(f"\n{len(rows)} channels, medians:")
print(f"  fit seconds (in process)        {med('fit_s'):.4f}")
print(f"  interval seconds (in process)   {med('iv_s'):.4f}")
print(f"  process cpu, --no-intervals     {med('cpu_none'):.3f}")
print(f"  process cpu, intervals          {med('cpu_new'):.3f}")
if base:
    print(f"  process cpu, intervals, BASE    {med('cpu_base'):.3f}")
    ratio = statistics.median(r["cpu_base"] / r["cpu_new"] for r in rows)
    extra = statistics.median((r["cpu_base"] - r["cpu_none"]) / max(r["cpu_new"] - r["cpu_none"], 1e-3) for r in rows)
    print(f"  median per-channel cpu ratio BASE/new: {ratio:.2f}; of the interval part alone: {extra:.2f}")
    print(f"  largest end difference against BASE (of the half-width): median {med('end_diff'):.2e}, max {max(r['end_diff'] for r in rows):.2e}")
PY

#!/usr/bin/env bash
# Speed benchmark for `goniofit fit` against scipy.optimize.least_squares(method='lm')
# on a vectorised numpy KBS model (benches/scipy_kbs_fit.py), measured side by side in one run.
#
# Data: a 10k-sample KBS hemisphere scan, sigma = 0.25 lambda, T = 2.5 lambda, 1 % relative
# noise (goniofit synth, seed 1). scipy starts from goniofit's automatic initial values: the
# grid point whose refinement won (the report's "start"), before any iteration. Two goniofit
# times are quoted: the whole fit (grid search for the start, its quick refinement on a
# subsample, LM, verdict), and the same run from the start on (without the grid search,
# which scipy does not do either). The final costs are compared twice: each tool's own,
# and both parameter sets under scipy's model.
# Needs python3 with numpy and scipy (pip install numpy scipy); not part of CI.
#
# Usage: bash benches/fit_vs_scipy.sh [repeats]
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-7}
cargo build --release --quiet
G=target/release/goniofit
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
$G synth --model kbs --params sigma=0.25,T=2.5,scale=1 --wavelength 1 --layout hemisphere \
  --grid 10x25x40 --noise 0.01 --seed 1 --out "$dir/h10k.csv" 2>/dev/null
init=$($G fit --model kbs --wavelength 1 --json "$dir/h10k.csv" | python3 -c '
import json, sys
d = json.load(sys.stdin)
print(",".join("%s=%r" % (k, d["start"][k]) for k in ("sigma", "T", "scale")))')
python3 - "$G" "$dir/h10k.csv" "$init" "$repeats" <<'PY'
import json, statistics, subprocess, sys
g, data, init, repeats = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
# Interleaved: one goniofit fit, then one scipy fit, `repeats` times, so that both see the
# same machine state (shared machines drift between fast and slow phases).
ours, ours_from_start, theirs, cost, final, sp = [], [], [], None, None, None
for _ in range(repeats):
    out = subprocess.run([g, "fit", "--model", "kbs", "--wavelength", "1", "--json", data],
                         capture_output=True, text=True)
    d = json.loads(out.stdout)
    ours.append(d["seconds"])
    ours_from_start.append(d["seconds"] - d["start_seconds"])
    cost = d["cost"]
    final = ",".join("%s=%r" % (k, d["params"][k]["value"]) for k in ("sigma", "T", "scale"))
    sp = json.loads(subprocess.run([sys.executable, "benches/scipy_kbs_fit.py", data, "--wavelength", "1",
                                    "--init", init, "--repeats", "1", "--also", final],
                                   capture_output=True, text=True, check=True).stdout)
    theirs.append(sp["seconds_median"])
sp["seconds_median"] = statistics.median(theirs)
m_ours = statistics.median(ours)
m_from = statistics.median(ours_from_start)
print(f"samples            {sp['n']}")
print(f"start              {init}")
print(f"goniofit fit       median {m_ours*1e3:9.2f} ms  cost {cost:.15e}  (runs: {', '.join(f'{t*1e3:.1f}' for t in ours)})")
print(f"scipy lm (numpy)   median {sp['seconds_median']*1e3:9.2f} ms  cost {sp['cost']:.15e}  nfev {sp['nfev']}  (runs: {', '.join(f'{t*1e3:.0f}' for t in theirs)})")
print(f"per-run ratios     {', '.join(f'{b/a:.1f}' for a, b in zip(ours, theirs))}")
print(f"  from the start   median {m_from*1e3:9.2f} ms  (the same runs without the grid search that finds the start)")
print(f"speed-up           {sp['seconds_median']/m_ours:.1f}x whole fit, {sp['seconds_median']/m_from:.1f}x from the same start"
      f"   cost ratio goniofit/scipy {cost/sp['cost']:.12f}")
# Both final parameter sets under one model (scipy's numpy series), so that the comparison
# of final costs does not depend on the two models' last-digit differences.
print(f"on scipy's model   goniofit's parameters cost {sp['also_cost']:.15e}, scipy's {sp['cost']:.15e}"
      f"  (ratio {sp['also_cost']/sp['cost']:.15f})")
PY

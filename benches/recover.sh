#!/usr/bin/env bash
# The larger recovery check: `goniofit recover --scenes N --seed S --json` at each seed
# (default 150 scenes at the three seeds 2718, 16180, 90210, which no test uses;
# tests/trust/recover.rs uses 11, 4242, 777, 31337 and 5).
# Prints per regime the ±2 s.e. coverage pooled over the seeds, and every confidently
# wrong scene (converged, a determined quantity off by more than 10 s.e. and 20 %) with the
# command that reproduces it. Exits 1 unless no scene is confidently wrong and every
# regime's pooled coverage lies in [0.90, 0.99].
#
# Usage: [SCENES=150] [SEEDS="2718 16180 90210"] [RAYON_NUM_THREADS=1] bash benches/recover.sh
set -euo pipefail
cd "$(dirname "$0")/.."
scenes=${SCENES:-150}
seeds=${SEEDS:-2718 16180 90210}
cargo build --release --quiet
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
for s in $seeds; do
  ./target/release/goniofit recover --scenes "$scenes" --seed "$s" --json > "$dir/$s.json"
done
python3 - "$dir" $seeds <<'PY'
import json, sys
d, seeds = sys.argv[1], sys.argv[2:]
cov, wrong, conv, total, secs = {}, [], 0, 0, 0.0
for s in seeds:
    r = json.load(open(f"{d}/{s}.json"))
    conv += r["converged"]; total += r["scenes"]; secs += r["total_seconds"]
    for res in r["results"]:
        reg = res["scene"]["regime"]
        for c in res["checks"]:
            if c["covered"] is not None:
                a = cov.setdefault(reg, [0, 0]); a[0] += c["covered"]; a[1] += 1
    wrong += [(s, o) for o in r["outliers"] if o["wrong"]]
print(f"seeds {' '.join(seeds)}, {total} scenes, converged {conv}, {secs:.1f} s of recover")
ok = not wrong
for reg in ["smooth", "intermediate", "rough", "grazing"]:
    inside, n = cov.get(reg, [0, 0])
    c = inside / n if n else float("nan")
    good = 0.90 <= c <= 0.99
    ok &= good
    print(f"  {reg:<13} coverage of ±2 s.e. {c:.3f} ({inside}/{n} truths){'' if good else '  OUTSIDE [0.90, 0.99]'}")
print(f"confidently wrong converged scenes: {len(wrong)}")
for s, o in wrong:
    print(f"  seed {s} scene {o['id']}: {o['recover_command']}")
sys.exit(0 if ok else 1)
PY

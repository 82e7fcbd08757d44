#!/bin/sh
# `goniofit fit --model auto` on every bundled RGL file and channel: the chosen model, the
# exit code and the wall time of each (21 fits; the 64 × 64 file takes ~25 s a channel).
# Usage: benches/rgl_fit_auto.sh [GONIOFIT_BIN]  (default target/release/goniofit)
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${1:-$root/target/release/goniofit}
printf '%-28s %-7s %-4s %-8s %s\n' file channel exit seconds model
for f in "$root"/data/rgl-epfl/*.bsdf; do
    for c in r g b; do
        start=$(date +%s.%N)
        report=$("$bin" fit --model auto --channel "$c" "$f" 2>&1)
        code=$?
        end=$(date +%s.%N)
        model=$(printf '%s\n' "$report" | sed -n 's/^ *model *= *//p' | head -1)
        printf '%-28s %-7s %-4s %-8.2f %s\n' "$(basename "$f")" "$c" "$code" \
            "$(echo "$end - $start" | bc)" "$model"
    done
done

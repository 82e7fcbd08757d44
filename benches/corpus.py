#!/usr/bin/env python3
"""The whole real-data corpus fitted the default way, checked against the reference optima.

Fits (kbs+lambert, BRDF, log residuals, the default start search, one thread):
  CUReT:   data/curet/curet.csv --wavelength 550 --by-group (61 samples);
  Cornell: data/cornell/{acryl_blue,cayman,garnet_red,krylon_blue}.astm --by-group (31
           channels each).
Each fit is classed against tests/ref/corpus_reference.csv (see tests/ref/corpus_reference.py):
  at-best    converged, inside the domain, cost <= cost_best * (1 + TOL);
  degenerate `degenerate` with a note, and the reference's best point is at an edge of the
             domain or no better than TOL below the best inside it... (see class_of);
  MISS       anything else (converged in a worse optimum, degenerate although an optimum
             inside the domain is the best known, or stopped without converging).
Times: the fit's own run time (JSON `seconds`, per dataset) and each file's wall time.

Usage: python3 benches/corpus.py EXE [--intervals] [--repeats N] [--json OUT]
(standard library only; run from the repository root). Prints one line per MISS or
degenerate fit, then the counts and the times (median and worst per dataset, of each file's fits, and
each file's wall time; the slowest fits by name; how many Cornell channels take over 0.1 s),
and how many fits the adequacy tests flag per corpus, with the count of each reason.
"""
import argparse
import csv
import json
import math
import statistics
import subprocess
import sys
import time

# Relative cost tolerance of "at the best known optimum": the reduced refit (sigma held in
# the rough regime) and the solver's ftol leave the cost a little above the reference's
# full --no-reduce optimum.
TOL = 1e-3
FILES = [
    ("curet", "data/curet/curet.csv", ["--wavelength", "550"]),
    ("cornell", "data/cornell/acryl_blue.astm", []),
    ("cornell", "data/cornell/cayman.astm", []),
    ("cornell", "data/cornell/garnet_red.astm", []),
    ("cornell", "data/cornell/krylon_blue.astm", []),
]
REF = "tests/ref/corpus_reference.csv"
# How many of the slowest fits to name, and the time a Cornell channel should stay under.
SLOWEST = 5
CHANNEL_BUDGET = 0.1


def reference(path=REF):
    with open(path) as f:
        return {(r["file"], r["group"]): r for r in csv.DictReader(l for l in f if not l.startswith("#"))}


def group_of(fit):
    """The group label of a --by-group fit from its input name `FILE [GROUP]`."""
    name = fit["input"]
    return name[name.rindex("[") + 1:-1]


def class_of(fit, ref):
    """at-best / degenerate / MISS with the reason (see the module doc)."""
    best = float(ref["cost_best"])
    inside = float(ref["cost_inside"])
    cost = fit["cost"]
    term = fit["termination"]
    if term == "degenerate":
        if not fit["notes"]:
            return "MISS", "degenerate without a note"
        if ref["edge_best"] != "none" or inside > best * (1 + TOL):
            return "degenerate", "the best known point is at an edge (" + ref["edge_best"] + ")"
        return "degenerate", f"an optimum inside the domain is known (cost {inside:.6g})"
    if fit["converged"] and cost is not None and cost <= best * (1 + TOL):
        return "at-best", ""
    if fit["converged"]:
        return "MISS", f"converged at cost {cost:.6g}, {cost / best - 1:.2%} above the best {best:.6g}"
    return "MISS", f"termination {term}, cost {cost}"


def run(exe, corpus, path, extra, intervals):
    args = [exe, "fit", "--model", "kbs+lambert", "--quantity", "brdf", "--residual", "log",
            "--by-group", "--json", "--threads", "1", *extra]
    if not intervals:
        args.append("--no-intervals")
    t0 = time.perf_counter()
    out = subprocess.run([*args, path], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if not out.stdout.strip():
        sys.exit(f"{path}: no report (exit {out.returncode}): {out.stderr.strip()}")
    return json.loads(out.stdout)["fits"], wall


def adequacy_lines(adequacy):
    """Per corpus: how many fits the adequacy verdict flags, by verdict and by reason."""
    for corpus in sorted({c for c, _, _ in adequacy.values()}):
        fits = [(v, codes) for c, v, codes in adequacy.values() if c == corpus]
        flagged = [(v, codes) for v, codes in fits if v in ("misfit", "noise")]
        verdicts = {v: sum(1 for w, _ in fits if w == v) for v in sorted({v for v, _ in fits})}
        reasons = {}
        for _, codes in flagged:
            for code in codes:
                reasons[code] = reasons.get(code, 0) + 1
        print(f"adequacy {corpus}: {len(flagged)} of {len(fits)} fits flagged ("
              + ", ".join(f"{k} {v}" for k, v in verdicts.items()) + "); reasons: "
              + (", ".join(f"{k} {v}" for k, v in sorted(reasons.items(), key=lambda kv: -kv[1]))
                 or "none"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("exe")
    ap.add_argument("--intervals", action="store_true", help="keep the profile intervals")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--json", help="write the per-fit classes and times here")
    a = ap.parse_args()
    ref = reference()
    classes, per_fit, per_file, rows, adequacy = {}, {}, {}, [], {}
    for _ in range(a.repeats):
        for corpus, path, extra in FILES:
            fits, wall = run(a.exe, corpus, path, extra, a.intervals)
            per_file.setdefault(path, []).append(wall)
            for f in fits:
                key = (path.rsplit("/", 1)[1], group_of(f))
                per_fit.setdefault(key, []).append(f["seconds"])
                if key not in classes:
                    c, why = class_of(f, ref[key])
                    classes[key] = c
                    adequacy[key] = (corpus, f["adequacy"]["verdict"],
                                     [r["code"] for r in f["adequacy"]["reasons"]])
                    rows.append({"file": key[0], "group": key[1], "class": c, "why": why,
                                 "cost": f["cost"], "cost_best": float(ref[key]["cost_best"]),
                                 "termination": f["termination"]})
                    if c != "at-best":
                        print(f"{c:10s} {key[0]} {key[1]}: {why}")
    counts = {c: list(classes.values()).count(c) for c in ("at-best", "degenerate", "MISS")}
    print(f"{len(classes)} fits: " + ", ".join(f"{v} {k}" for k, v in counts.items()))
    adequacy_lines(adequacy)
    fit_med = {k: statistics.median(v) for k, v in per_fit.items()}
    cornell = [v for k, v in fit_med.items() if k[0].endswith(".astm")]
    curet = [v for k, v in fit_med.items() if not k[0].endswith(".astm")]
    print(f"per dataset (fit's run time, median of {a.repeats}): Cornell channel median "
          f"{statistics.median(cornell):.4f} s, worst {max(cornell):.4f} s; CUReT sample "
          f"median {statistics.median(curet):.4f} s, worst {max(curet):.4f} s")
    slow = sorted(fit_med.items(), key=lambda kv: -kv[1])[:SLOWEST]
    print(f"slowest fits: " + ", ".join(f"{k[0]} {k[1]} {v:.3f} s" for k, v in slow)
          + f"; Cornell channels over {CHANNEL_BUDGET} s: "
          + str(sum(v > CHANNEL_BUDGET for v in cornell)) + f" of {len(cornell)}")
    by_file = {}
    for k, v in fit_med.items():
        by_file.setdefault(k[0], []).append(v)
    print("fit time per file (median / worst of its fits): " + ", ".join(
        f"{f} {statistics.median(v):.4f} / {max(v):.4f} s" for f, v in by_file.items()))
    for r in rows:
        r["seconds"] = fit_med[(r["file"], r["group"])]
    files = {k: statistics.median(v) for k, v in per_file.items()}
    print("per file (wall, median of %d): " % a.repeats
          + ", ".join(f"{k.rsplit('/', 1)[1]} {v:.3f} s" for k, v in files.items())
          + f"; median {statistics.median(files.values()):.3f} s, worst {max(files.values()):.3f} s")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"counts": counts, "fits": rows, "file_seconds": files,
                       "cornell_channel_seconds": {"median": statistics.median(cornell),
                                                   "worst": max(cornell)},
                       "curet_sample_seconds": {"median": statistics.median(curet),
                                                "worst": max(curet)},
                       "fit_seconds_per_file": {f: {"median": statistics.median(v), "worst": max(v)}
                                                for f, v in by_file.items()}}, f, indent=1)
    sys.exit(1 if counts["MISS"] else 0)


if __name__ == "__main__":
    main()

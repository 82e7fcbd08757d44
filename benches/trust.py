#!/usr/bin/env python3
"""The trust matrix: goniofit's default fit of every (model, residual, dataset) case of
tests/ref/trust_reference.csv, classed against that independent multi-start reference.

Each case is `goniofit fit --model M --residual R ARGS` (ARGS: the dataset as a user
selects it; the defaults otherwise), run with --json (and --no-intervals, which does not
change the fit). Classes, with best = min(the reference's best cost, goniofit's cost):
  best        converged at a cost within TOL (relative) of best;
  degenerate  `degenerate`, and the reference's best point is at an edge of the domain too
              (honestly degenerate);
  LIE         converged at a cost more than TOL above best;
  MISS        not converged, or degenerate where the reference's best point is inside the
              domain.

Usage: python3 benches/trust.py EXE [--only SUBSTRING] [--notes FILE] [--ref TABLE]
[--factors] (standard library only; from the repository root). With --factors the cases
are those of tests/ref/factors_reference.csv, fitted with kbs+lambert and the lobe's
factors (`--fresnel dielectric --shadowing smith`). Prints each case that is not `best`
with its command, goniofit's cost and the reference's, then the counts per class.
Exit status 1 when there is a LIE or a MISS.
"""
import argparse
import csv
import json
import subprocess
import sys

TOL = 1e-4
REF = "tests/ref/trust_reference.csv"
FACTORS_REF = "tests/ref/factors_reference.csv"
# The model of the factors table's cases (its rows name no model).
FACTORS_MODEL = ["kbs+lambert", "--fresnel", "dielectric", "--shadowing", "smith"]


def reference(path=REF):
    with open(path) as f:
        return list(csv.DictReader(l for l in f if not l.startswith("#")))


def model_args(row):
    return [row["model"]] if "model" in row else FACTORS_MODEL


def command(row):
    return ["fit", "--model", *model_args(row), "--residual", row["residual"],
            *row["args"].split()]


def run(exe, row):
    out = subprocess.run([exe, *command(row), "--json", "--no-intervals", "--threads", "1"],
                         capture_output=True, text=True)
    if not out.stdout.strip():
        return None, out.stderr.strip()
    return json.loads(out.stdout), ""


def class_of(fit, row):
    """(class, why) of goniofit's fit against the reference row (see the module doc)."""
    ref = float(row["cost_best"])
    cost = fit["cost"] if fit["cost"] is not None else float("inf")
    best = min(ref, cost)
    term = fit["termination"]
    at_edge = row["edge_best"] not in ("none", "sigma-cap")
    if term == "degenerate":
        if at_edge:
            return "degenerate", f"the reference's best point is at an edge ({row['edge_best']})"
        return "MISS", (f"degenerate at cost {cost:.6g}; the reference's best {ref:.6g} "
                        f"is inside the domain")
    if fit["converged"] and cost <= best * (1 + TOL):
        return "best", ""
    if fit["converged"]:
        return "LIE", f"converged ({term}) at cost {cost:.6g}, {cost / best - 1:.3g} above {best:.6g}"
    return "MISS", f"{term} at cost {cost:.6g} (reference {ref:.6g})"


def describe(row, fit, cls, why):
    params = {k: v["value"] for k, v in fit["params"].items()} if fit else {}
    gp = ",".join(f"{k}={v:.6g}" for k, v in params.items())
    cmd = "goniofit " + " ".join(command(row))
    return (f"{cls:10s} {case(row)}: {why}\n"
            f"    {cmd}\n"
            f"    goniofit:  {fit['termination'] if fit else '-'} cost {fit['cost'] if fit else '-'} {gp}\n"
            f"    reference: cost {row['cost_best']} edge {row['edge_best']} "
            f"{row['params_best'].replace(';', ',')}\n"
            f"    reference inside the domain: cost {row['cost_inside']} "
            f"{row.get('params_inside', '').replace(';', ',')}")


def case(row):
    return f"{row['dataset']} {' '.join(model_args(row))} {row['residual']}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("exe")
    ap.add_argument("--only", default="", help="cases whose dataset/model/residual contain this")
    ap.add_argument("--notes", help="also write the non-best cases to this file")
    ap.add_argument("--ref", default=REF, help=f"the reference table (default {REF})")
    ap.add_argument("--factors", action="store_true",
                    help=f"the factors' cases ({FACTORS_REF}) with {' '.join(FACTORS_MODEL)}")
    a = ap.parse_args()
    if a.factors:
        a.ref = FACTORS_REF
    counts = {c: 0 for c in ("best", "degenerate", "LIE", "MISS")}
    lines = []
    for row in reference(a.ref):
        if a.only not in case(row):
            continue
        fit, err = run(a.exe, row)
        if fit is None:
            cls, why = "MISS", f"no report: {err}"
        else:
            cls, why = class_of(fit, row)
        counts[cls] += 1
        if cls != "best":
            text = describe(row, fit, cls, why)
            lines.append(text)
            print(text, flush=True)
    total = sum(counts.values())
    summary = f"{total} cases: " + ", ".join(f"{v} {k}" for k, v in counts.items())
    print(summary)
    if a.notes:
        with open(a.notes, "w") as f:
            f.write(summary + "\n\n" + "\n".join(lines) + "\n")
    sys.exit(1 if counts["LIE"] or counts["MISS"] else 0)


if __name__ == "__main__":
    main()

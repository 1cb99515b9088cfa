#!/usr/bin/env python3
"""Choose the `auto` portfolio's thresholds and plans on the generated families (issue 28).

A documented sweep with a held-back part (notes/portfolio.md has the method and results):

1. **Instances.** `scripts/families.sh OUT/families` writes the training part (seeds 1, 2)
   and the held-back part (seeds 1001, 1002). The sweep keeps the matrix families
   (`random-sop`, `atsp`, `symmetric`, `near-symmetric`, `compiler-dag`, `time-window`,
   `generalized`) with
   n <= --max-n (500 by default, for time). `geometric-sparse` is left out: the geometric rules
   (`geometric-free` and the catch-all) were chosen by timed races of their plans on the
   `uniform` family (`scripts/plan_race.py`, notes/portfolio.md), since an evaluation count
   means different work in the two-level search and in the array phases.
2. **Plan portfolios.** Every rule of the built-in portfolio (`src/solvers/auto/portfolio.toml`)
   becomes a one-rule portfolio file `OUT/cand/plan-NAME.toml` (its beam and phases as a
   catch-all), plus plan variants defined below (`VARIANTS`); all but the catch-all's plan
   (which no matrix instance reaches) run. Each runs on every instance:
   `cellseq solve FILE --portfolio CAND --max-evals N --seed S --json --explain --no-bound`,
   one thread, a fixed evaluation budget (deterministic: the result does not depend on the
   machine's load). Runs are cached in `OUT/runs.jsonl` (an interrupted sweep resumes).
3. **Candidate portfolios** are decision lists in the built-in's shape: a symmetric rule (on
   or off), a free rule (`free_density <= F`), a sparse rule (`closure_density < D`), a
   medium rule (`D <= closure_density < 0.8`, `cells <= K`) and a large-medium one (more
   cells), the built-in's dense rule (closure density >= 0.8: its plans and its beam bound
   were chosen by timed races on the dense `random-sop` and `time-window` instances,
   notes/portfolio.md; the sweep keeps it as it is) and the catch-all.
   The threshold values tried are the built-in's and the midpoints between consecutive
   feature values seen on the training part; for each set of thresholds every rule gets the plan (of all plan portfolios) with the
   least total score over the training instances it takes (ties: the built-in's plan). As every rule's plan has been run on every instance, a candidate's
   result on an instance is the result of the plan it selects there (the same run: the
   solver is deterministic under an evaluation budget); the held-back check below runs the
   chosen portfolio file for real and compares.
4. **Score**: per instance (cost + 1) / (best cost of any plan on it + 1); a candidate's
   score is the mean over the training instances. The pick is the candidate of least
   training score; ties go to the one closest to the built-in (fewest changed values).
5. **Held-back report**: the pick against the built-in on the held-back part (composed from
   the plan runs, then confirmed by running both portfolio files), per family and rule.
6. **Validation** (`--validate`): TSPLIB SOP and PCGTSPLIB files with the built-in and the
   pick at the same budget; reported, never used for choosing.

usage: portfolio_sweep.py OUT [--cellseq PATH] [--families DIR] [--max-n 500] [--evals 10000000]
                          [--seeds 1] [--jobs 1] [--keep-symmetric] [--validate DIR...]

Writes OUT/report.md (tables), OUT/pick.toml (the chosen portfolio) and OUT/runs.jsonl.
Run it under `nice`; it is untimed (evaluation budgets only).
"""

import argparse
import hashlib
import concurrent.futures as cf
import json
import os
import re
import statistics
import subprocess
import sys
import threading
import tomllib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
from sop_common import cellseq_solve  # noqa: E402
import safe_files  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILT_IN = os.path.join(ROOT, "crates", "cellseq", "src", "solvers", "auto", "portfolio.toml")

# Plan variants beside the built-in rules' plans (the free/sparse boundary): `atsp` first,
# then `ils` from its best in the sparse rule's narrow acceptance band.
VARIANTS = {
    "atsp-ils": {
        "beam": {"share": 0.1},
        "phases": [
            {"solver": "atsp", "share": 0.5},
            {"solver": "ils", "share": 1.0, "start": "best",
             "params": {"accept": 0.01, "shift-repair": 2}},
        ],
    },
}
MATRIX_FAMILIES = ("random-sop", "atsp", "symmetric", "near-symmetric", "compiler-dag",
                   "time-window", "generalized")


# ---- TOML output (the portfolio format's small subset) ----

def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, dict):
        return "{ " + ", ".join("%s = %s" % (toml_key(k), toml_value(x))
                                for k, x in v.items()) + " }"
    raise TypeError(v)


def toml_key(k):
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def rule_text(name, rule, when=None):
    out = ["[[rule]]", "name = %s" % json.dumps(name)]
    if when:
        out.append("when = %s" % toml_value(when))
    out.append("beam = %s" % toml_value(rule["beam"]))
    for key in ("phases", "after_beam"):
        if key in rule:
            out.append("%s = [" % key)
            out += ["    %s," % toml_value(p) for p in rule[key]]
            out.append("]")
    return "\n".join(out) + "\n"


def portfolio_text(beam, rules):
    """rules: list of (name, rule dict, when dict or None); the last has no `when`."""
    head = "[beam]\nmax_cells = %d\nmin_seconds = %r\n" % (beam["max_cells"],
                                                          beam["min_seconds"])
    return head + "".join("\n" + rule_text(n, r, w) for n, r, w in rules)


def plan_of(rule):
    """A rule's plan: its beam, phases and after-beam phases."""
    return {k: rule[k] for k in ("beam", "phases", "after_beam") if k in rule}


def load_plans():
    with open(BUILT_IN, "rb") as f:
        doc = tomllib.load(f)
    plans = {r["name"]: plan_of(r) for r in doc["rule"]}
    plans.update(VARIANTS)
    return doc["beam"], plans, doc["rule"]


def geometric_rules(rules):
    """The built-in's rules for geometric instances (`when.geometric = true`), kept as they
    are in every candidate: no matrix instance reaches them, so the sweep cannot choose them."""
    return [(r["name"], plan_of(r), r["when"])
            for r in rules if r.get("when", {}).get("geometric") is True]


# ---- candidates ----

# The built-in rules' shape. `medium` and `large-medium` (split <= closure_density < DENSE)
# are the built-in's `sparse` region cut at `split`: their home plan is the sparse one, so a
# split of DENSE leaves them empty and the candidate is the built-in.
DENSE = 0.8
BUILT_IN_CAND = {"sym": True, "free": 0.001, "split": DENSE, "cells": 300,
                 "plans": {"symmetric": "symmetric", "free": "free", "sparse": "sparse",
                           "medium": "sparse", "large-medium": "sparse",
                           "dense": "dense"}}
REGIONS = ("symmetric", "free", "sparse", "medium", "large-medium", "dense")


def region(c, f):
    """The rule (region) of candidate `c` an instance with features `f` falls in."""
    if f["geometric"]:
        return "default"
    if c["sym"] and f["symmetric"]:
        return "symmetric"
    if f["free_density"] <= c["free"]:
        return "free"
    if f["closure_density"] < c["split"]:
        return "sparse"
    if f["closure_density"] < DENSE:
        return "medium" if f["cells"] <= c["cells"] else "large-medium"
    return "dense"


def choose(c, f):
    """The plan name candidate `c` runs on an instance with features `f`."""
    r = region(c, f)
    return c["plans"].get(r, r)


def candidate_rules(c, plans, geometric=()):
    pl = lambda r: plans[c["plans"][r]]  # noqa: E731
    rules = []
    if c["sym"]:
        rules.append(("symmetric", pl("symmetric"), {"geometric": False, "symmetric": True}))
    rules.append(("free", pl("free"), {"geometric": False, "free_density": {"max": c["free"]}}))
    rules.append(("sparse", pl("sparse"),
                  {"geometric": False, "closure_density": {"below": c["split"]}}))
    if c["split"] < DENSE:
        rules.append(("medium", pl("medium"), {
            "geometric": False, "closure_density": {"below": DENSE},
            "cells": {"max": c["cells"]}}))
        rules.append(("large-medium", pl("large-medium"),
                      {"geometric": False, "closure_density": {"below": DENSE}}))
    rules.append(("dense", pl("dense"), {"geometric": False,
                                         "closure_density": {"min": DENSE}}))
    rules.extend(geometric)
    rules.append(("default", plans["default"], None))
    return rules


def midpoints(values, keep=None):
    v = sorted(set(values))
    mids = [(a + b) / 2 for a, b in zip(v, v[1:])]
    return [m for m in mids if keep is None or keep(m)]


def nice_round(x, lo, hi):
    """x rounded to the fewest significant digits that keep it in the middle half of
    (lo, hi) (so the file reads well and the bound stays away from both sides), else x."""
    q = (hi - lo) / 4
    for digits in range(1, 8):
        r = float("%.*g" % (digits, x))
        if lo + q <= r <= hi - q:
            return r
    return x


def grid(train_feats, keep_symmetric=False):
    fd = [f["free_density"] for f in train_feats]
    cd = [f["closure_density"] for f in train_feats]
    cells = [f["cells"] for f in train_feats]

    def rounded(values, keep):
        v = sorted(set(values))
        return [nice_round((a + b) / 2, a, b) for a, b in zip(v, v[1:])
                if keep((a + b) / 2)]
    frees = sorted({0.001} | set(rounded(fd, lambda m: m < 0.1)))
    splits = sorted({DENSE} | set(rounded(cd, lambda m: 0.2 < m < DENSE)))
    cellss = sorted({300} | {int(m) for m in midpoints(cells)})
    for sym in ((True,) if keep_symmetric else (True, False)):
        for fr in frees:
            for sp in splits:
                for k in cellss:
                    yield {"sym": sym, "free": fr, "split": sp, "cells": k}


def fit_plans(t, files, sc, feats, names):
    """Thresholds `t` with the best plan per region on `files` (ties: the built-in's plan);
    returns (candidate, mean score)."""
    groups = {}
    for f in files:
        groups.setdefault(region(t, feats[f]), []).append(f)
    plans, total = {}, 0.0
    for r in REGIONS:
        fs = groups.get(r, [])
        home = BUILT_IN_CAND["plans"][r]
        sums = {p: sum(sc[f][p] for f in fs) for p in names}
        best = min(sums.values()) if fs else 0.0
        plans[r] = home if sums[home] <= best + 1e-9 else min(
            (p for p in names if sums[p] <= best + 1e-9))
        total += sums[plans[r]]
    return dict(t, plans=plans), total / len(files)


def distance(c):
    d = sum(c[k] != BUILT_IN_CAND[k] for k in ("sym", "free", "split", "cells"))
    return d + sum(c["plans"][r] != BUILT_IN_CAND["plans"][r] for r in REGIONS)


# ---- runs ----

def instance_n(path):
    m = re.search(r"_n-(\d+)", os.path.basename(path))
    return int(m.group(1)) if m else None


def family_of(path):
    return os.path.basename(path).split("_n-")[0]


def instances(out, max_n, fam=None):
    fam = fam or os.path.join(out, "families")
    if not os.path.isdir(os.path.join(fam, "heldback")):
        env = dict(os.environ)
        subprocess.run([os.path.join(ROOT, "scripts", "families.sh"), fam], check=True,
                       env=env, stdout=subprocess.DEVNULL)
    parts = {}
    for part in ("train", "heldback"):
        d = os.path.join(fam, part)
        parts[part] = sorted(
            os.path.join(d, f) for f in os.listdir(d)
            if family_of(f) in MATRIX_FAMILIES and (instance_n(f) or 0) <= max_n)
    return parts


class Runs:
    def __init__(self, path):
        self.path, self.lock, self.done = path, threading.Lock(), {}
        if os.path.exists(path):
            with open(path) as f:
                for line in f:
                    if line.strip():
                        r = json.loads(line)
                        self.done[(r["file"], r["plan"], r["seed"], r["evals"])] = r

    def get(self, file, plan, seed, evals):
        return self.done.get((os.path.abspath(file), plan, seed, evals))

    def add(self, r):
        with self.lock:
            self.done[(r["file"], r["plan"], r["seed"], r["evals"])] = r
            safe_files.append_line(self.path, json.dumps(r))


def solve(binary, file, portfolio, seed, evals):
    return cellseq_solve(binary, file, ["--max-evals", str(evals)], seed, portfolio,
                         explain=True)


def run_all(a, runs, jobs):
    """jobs: list of (file, plan name, portfolio path or None, seed)."""
    todo = [j for j in jobs if runs.get(j[0], j[1], j[3], a.evals) is None]
    print("%d runs, %d cached" % (len(jobs), len(jobs) - len(todo)), file=sys.stderr)

    def one(j):
        file, plan, port, seed = j
        r = solve(a.cellseq, file, port, seed, a.evals)
        runs.add({"file": os.path.abspath(file), "plan": plan, "seed": seed, "evals": a.evals,
                  "cost": r["cost"], "best_known": r.get("best_known"),
                  "rule": r["explain"]["rule"], "features": r["explain"]["features"],
                  "elapsed_s": r["elapsed_s"]})
    with cf.ThreadPoolExecutor(max_workers=a.jobs) as ex:
        for k, _ in enumerate(ex.map(one, todo)):
            if (k + 1) % 50 == 0:
                print("  %d/%d" % (k + 1, len(todo)), file=sys.stderr)


# ---- scoring and the report ----

def table(rows, header):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(x) for x in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def scores_of(files, plans, runs, a):
    """{file: {plan: mean score over seeds}}, {file: features}."""
    sc, feats = {}, {}
    for f in files:
        per = {}
        for seed in a.seeds:
            costs = {p: runs.get(f, p, seed, a.evals)["cost"] for p in plans}
            best = min(costs.values())
            for p, c in costs.items():
                per.setdefault(p, []).append((c + 1) / (best + 1))
        sc[f] = {p: statistics.mean(v) for p, v in per.items()}
        feats[f] = runs.get(f, plans[0], a.seeds[0], a.evals)["features"]
    return sc, feats


def mean_score(c, files, sc, feats):
    return statistics.mean(sc[f][choose(c, feats[f])] for f in files)


def by_family(c_pick, files, sc, feats):
    rows = []
    fams = sorted({family_of(f) for f in files})
    for fam in fams:
        fs = [f for f in files if family_of(f) == fam]
        b = statistics.mean(sc[f][choose(BUILT_IN_CAND, feats[f])] for f in fs)
        p = statistics.mean(sc[f][choose(c_pick, feats[f])] for f in fs)
        changed = sum(choose(BUILT_IN_CAND, feats[f]) != choose(c_pick, feats[f]) for f in fs)
        rows.append((fam, len(fs), "%.4f" % b, "%.4f" % p, changed))
    return rows


def plan_table(files, plans, sc, feats):
    rows = []
    for f in files:
        ft = feats[f]
        rows.append([os.path.basename(f).rsplit(".", 1)[0], "%.4f" % ft["free_density"],
                     "%.3f" % ft["closure_density"], "y" if ft["symmetric"] else "n",
                     choose(BUILT_IN_CAND, ft)] + ["%.3f" % sc[f][p] for p in plans])
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--cellseq", default=os.path.join(ROOT, "target", "release", "cellseq"))
    ap.add_argument("--families", help="a scripts/families.sh OUTDIR to use (default: "
                    "write one into OUT/families)")
    ap.add_argument("--max-n", type=int, default=500)
    ap.add_argument("--evals", type=int, default=10_000_000)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--keep-symmetric", action="store_true",
                    help="only candidates that keep the symmetric rule")
    ap.add_argument("--validate", nargs="*", default=None,
                    help="directories of TSPLIB SOP / PCGTSPLIB files to validate on")
    a = ap.parse_args()
    a.cellseq = os.path.abspath(a.cellseq)
    os.makedirs(os.path.join(a.out, "cand"), exist_ok=True)
    os.environ.setdefault("CELLSEQ", a.cellseq)

    beam, plans, built_in_rules = load_plans()
    geometric = geometric_rules(built_in_rules)
    plan_files = {}
    for name, rule in plans.items():
        path = os.path.abspath(os.path.join(a.out, "cand", "plan-%s.toml" % name))
        safe_files.write_text(path, portfolio_text(beam, [(name, rule, None)]))
        plan_files[name] = path
    # the catch-all's and the geometric rules' plans are left out: no matrix instance
    # reaches them
    names = sorted(p for p in plans if p != "default" and p not in {g[0] for g in geometric})
    parts = instances(a.out, a.max_n, a.families)
    runs = Runs(os.path.join(a.out, "runs.jsonl"))
    jobs = [(f, p, plan_files[p], s) for part in ("train", "heldback") for f in parts[part]
            for p in names for s in a.seeds]
    run_all(a, runs, jobs)

    # the pick, on the training part
    tr_sc, tr_ft = scores_of(parts["train"], names, runs, a)
    cands = list(grid(list(tr_ft.values()), a.keep_symmetric))
    scored = []
    for t in cands:
        c, score = fit_plans(t, parts["train"], tr_sc, tr_ft, names)
        scored.append((score, distance(c), c))
    best = min(s for s, _, _ in scored)
    ties = [t for t in scored if t[0] <= best + 1e-12]
    pick = min(ties, key=lambda t: (t[1], abs(t[2]["free"] - 0.001), abs(t[2]["split"] - 0.8),
                                    abs(t[2]["cells"] - 300)))[2]
    pick_path = os.path.join(a.out, "pick.toml")
    pick_text = portfolio_text(beam, candidate_rules(pick, plans, geometric))
    safe_files.write_text(
        pick_path, "# chosen by scripts/portfolio_sweep.py on the training families\n" + pick_text)
    # runs of the pick's file are cached under a label naming its content
    pick_label = "file:pick-" + hashlib.sha1(pick_text.encode()).hexdigest()[:12]
    builtin_path = os.path.join(a.out, "cand", "built-in.toml")
    safe_files.write_text(
        builtin_path, portfolio_text(beam, candidate_rules(BUILT_IN_CAND, plans, geometric)))

    # held back: composed, then both portfolio files for real
    hb_sc, hb_ft = scores_of(parts["heldback"], names, runs, a)
    confirm = [(f, pick_label, os.path.abspath(pick_path), s)
               for f in parts["heldback"] for s in a.seeds]
    confirm += [(f, "file:built-in", None, s) for f in parts["heldback"] for s in a.seeds]
    run_all(a, runs, confirm)
    mismatches = []
    for f in parts["heldback"]:
        for s in a.seeds:
            for label, c in ((pick_label, pick), ("file:built-in", BUILT_IN_CAND)):
                real = runs.get(f, label, s, a.evals)["cost"]
                composed = runs.get(f, choose(c, hb_ft[f]), s, a.evals)["cost"]
                if real != composed:
                    mismatches.append((os.path.basename(f), label, s, real, composed))

    rep = ["# Portfolio sweep\n",
           "Budget %d evaluations, seeds %s, n <= %d; %d training and %d held-back instances; "
           "%d candidates.\n" % (a.evals, a.seeds, a.max_n, len(parts["train"]),
                                 len(parts["heldback"]), len(cands)),
           "Pick: `%s` (built-in: `%s`).\n" % (json.dumps(pick), json.dumps(BUILT_IN_CAND)),
           "Training mean score: pick %.4f, built-in %.4f, best single plan everywhere %s.\n" % (
               mean_score(pick, parts["train"], tr_sc, tr_ft),
               mean_score(BUILT_IN_CAND, parts["train"], tr_sc, tr_ft),
               ", ".join("%s %.4f" % (p, statistics.mean(tr_sc[f][p] for f in parts["train"]))
                         for p in names)),
           "Held-back mean score: pick %.4f, built-in %.4f; oracle (best plan per instance) "
           "1.0000.\n" % (mean_score(pick, parts["heldback"], hb_sc, hb_ft),
                          mean_score(BUILT_IN_CAND, parts["heldback"], hb_sc, hb_ft)),
           "Composed results against the portfolio files run for real: %s.\n" % (
               "identical on every held-back run" if not mismatches
               else "%d differ: %s" % (len(mismatches), mismatches)),
           "\n## Per family (mean score; changed = instances whose plan differs)\n\n",
           "### Training\n\n",
           table(by_family(pick, parts["train"], tr_sc, tr_ft),
                 ["family", "instances", "built-in", "pick", "changed"]),
           "\n### Held back\n\n",
           table(by_family(pick, parts["heldback"], hb_sc, hb_ft),
                 ["family", "instances", "built-in", "pick", "changed"]),
           "\n## Every plan on every training instance (score; 1 = best plan there)\n\n",
           table(plan_table(parts["train"], names, tr_sc, tr_ft),
                 ["instance", "free_density", "closure", "sym", "built-in rule"] + names),
           "\n## Every plan on every held-back instance\n\n",
           table(plan_table(parts["heldback"], names, hb_sc, hb_ft),
                 ["instance", "free_density", "closure", "sym", "built-in rule"] + names)]

    if a.validate is not None:
        vfiles = sorted(os.path.join(d, f) for d in a.validate for f in os.listdir(d)
                        if f.endswith((".sop", ".pcglns")))
        vjobs = [(f, pick_label, os.path.abspath(pick_path), s) for f in vfiles for s in a.seeds]
        vjobs += [(f, "file:built-in", None, s) for f in vfiles for s in a.seeds]
        run_all(a, runs, vjobs)
        rows = []
        for d in a.validate:
            fs = [f for f in vfiles if os.path.dirname(f) == d]
            for label in ("file:built-in", pick_label):
                gaps, at = [], 0
                for f in fs:
                    for s in a.seeds:
                        r = runs.get(f, label, s, a.evals)
                        bk = r["best_known"]
                        if bk is not None:
                            gaps.append(100 * (r["cost"] - bk) / bk if bk else 0.0)
                            at += r["cost"] <= bk
                diff = sum(runs.get(f, pick_label, s, a.evals)["cost"]
                           != runs.get(f, "file:built-in", s, a.evals)["cost"]
                           for f in fs for s in a.seeds)
                rows.append((os.path.basename(d.rstrip("/")), label[5:17], len(fs),
                             "%.3f" % statistics.mean(gaps) if gaps else "–",
                             "%d/%d" % (at, len(gaps)), diff))
        rep += ["\n## Validation (reported, not used for choosing)\n\n",
                table(rows, ["set", "portfolio", "files", "mean gap %", "at or below best known",
                             "results that differ"])]
    safe_files.write_text(os.path.join(a.out, "report.md"), "".join(rep))
    print("".join(rep[:6]))
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Writes results/benchmarks.md from harness result files (issue 6).

usage: scripts/benchmarks_report.py [--results DIR] [--out FILE] [--note TEXT]
  (defaults: DIR = results/benchmarks, FILE = results/benchmarks.md)

Reads, when present:
  DIR/<plan>/results.csv   for the SOP plans (sop, sop-auto-5x10s, sop-auto-10s, sop-auto-5x1s, sop-quick, sop-solvers-1s), the PCGTSP plans
                           (pcgtsp, pcgtsp-quick) and the scale plan (scale), as written by
                           `cellseq run`;
  DIR/scale-1e6.csv        rows appended by `cargo run --release --example scale -- ... csv=`;
  DIR/machine.txt          `key: value` lines written by scripts/benchmarks.sh (nproc, CPU,
                           date, load average, git commit);
  experiments/sop-anchors.csv  the peer figures quoted in issue 6.
Every number of the output comes from these files; nothing is typed in here.
"""

import argparse
import csv
import os
import statistics
import sys
from collections import OrderedDict, defaultdict

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
import safe_files  # noqa: E402

EPS = 1e-9
SOP_PLANS = ["sop", "sop-auto-5x10s", "sop-auto-10s", "sop-auto-5x1s", "sop-quick", "sop-solvers-1s"]
PCG_PLANS = ["pcgtsp", "pcgtsp-quick"]


def fnum(x):
    try:
        if x is None or x == "":
            return None
        return float(x)
    except ValueError:
        return None


def fmt(x, d=2):
    if x is None:
        return "–"
    if abs(x - round(x)) < EPS and abs(x) < 1e15:
        return str(int(round(x)))
    return f"{x:.{d}f}"


def pct(x, d=2):
    return "–" if x is None else f"{x:.{d}f} %"


def load(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def gap(cost, ref):
    if cost is None or ref is None or ref == 0:
        return None
    return 100.0 * (cost - ref) / abs(ref)


def summarize(rows):
    """Groups rows by (solver_id, instance) in file order -> per-instance medians."""
    groups = OrderedDict()
    for r in rows:
        groups.setdefault((r["solver_id"], r["instance"]), []).append(r)
    out = []
    for (sid, inst), rs in groups.items():
        ok = [r for r in rs if r["feasible"] == "true" and fnum(r["cost"]) is not None]
        costs = [fnum(r["cost"]) for r in ok]
        bks = fnum(rs[0]["best_known"])
        lbs = [fnum(r["lower_bound"]) for r in rs if fnum(r["lower_bound"]) is not None]
        lb = max(lbs) if lbs else None
        med = statistics.median(costs) if costs else None
        out.append(
            {
                "solver": sid,
                "instance": inst,
                "n": rs[0]["n"],
                "runs": len(rs),
                "feasible": len(ok),
                "budget": rs[0]["budget"],
                "bks": bks,
                "median": med,
                "best": min(costs) if costs else None,
                "gap": gap(med, bks),
                "lb": lb,
                "cert": gap(med, lb),
                "proven": any(r["proven_optimal"] == "true" for r in rs),
                "time": statistics.median([float(r["wall_elapsed_s"]) for r in rs]),
                "errors": sorted({r["error"] for r in rs if r["error"]}),
                "air": statistics.median(
                    [fnum(r["air_length"]) for r in ok if fnum(r["air_length"]) is not None]
                )
                if ok
                else None,
                "lifts": statistics.median([fnum(r["lifts"]) for r in ok if fnum(r.get("lifts")) is not None])
                if ok and any(fnum(r.get("lifts")) is not None for r in ok)
                else None,
                "gen_params": rs[0]["gen_params"],
                "seeds": sorted({r["seed"] for r in rs}),
            }
        )
    return out


def instance_table(lines, recs):
    lines.append(
        "| instance | n | best known | ours median | best of runs | gap to best known | "
        "lower bound | certified gap | proven | median time (s) | runs |"
    )
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in recs:
        lines.append(
            f"| {r['instance']} | {r['n']} | {fmt(r['bks'])} | {fmt(r['median'])} | "
            f"{fmt(r['best'])} | {pct(r['gap'])} | {fmt(r['lb'])} | {pct(r['cert'])} | "
            f"{'yes' if r['proven'] else ''} | {r['time']:.2f} | "
            f"{r['feasible']}/{r['runs']}{' ' + '; '.join(r['errors']) if r['errors'] else ''} |"
        )


def solver_stats(recs):
    gaps = [r["gap"] for r in recs if r["gap"] is not None]
    at = sum(1 for g in gaps if g <= EPS)
    below = sum(1 for g in gaps if g < -EPS)
    worst = sorted((r for r in recs if r["gap"] is not None), key=lambda r: -r["gap"])
    certs = [r["cert"] for r in recs if r["cert"] is not None]
    return {
        "count": len(recs),
        "with_bks": len(gaps),
        "mean": statistics.mean(gaps) if gaps else None,
        "at": at,
        "below": below,
        "worst": worst,
        "proven": sum(1 for r in recs if r["proven"]),
        "with_lb": len(certs),
        "mean_cert": statistics.mean(certs) if certs else None,
        "time": statistics.mean([r["time"] for r in recs]) if recs else None,
    }


def load_anchors(path):
    anchors = defaultdict(dict)
    if not os.path.exists(path):
        return anchors
    with open(path, newline="") as f:
        rows = [l for l in f if not l.startswith("#")]
    for r in csv.DictReader(rows):
        key = r["kind"] if not r["instance"] else r["instance"]
        anchors[r["peer"]][key] = float(r["value"])
    return anchors


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--results", default="results/benchmarks")
    ap.add_argument("--out", default="results/benchmarks.md")
    ap.add_argument("--anchors", default="experiments/sop-anchors.csv")
    args = ap.parse_args()
    out = args.out
    rdir = args.results.rstrip("/")
    anchors = load_anchors(args.anchors)
    lkh = anchors.get("LKH-3 3.0.6", {})

    machine = OrderedDict()
    mpath = os.path.join(args.results, "machine.txt")
    if os.path.exists(mpath):
        for l in open(mpath):
            if ":" in l:
                k, v = l.split(":", 1)
                machine[k.strip()] = v.strip()

    L = ["# cellseq benchmarks (issue 6)", ""]
    L.append(
        "Generated by `scripts/benchmarks.sh` (which runs the plans with `cellseq run PLAN "
        "--threads 1`, then `scripts/benchmarks_report.py`). Every number below is read from "
        f"`{rdir}/<plan>/results.csv`, `{rdir}/scale-1e6.csv` and `{rdir}/machine.txt`; the "
        "peer figures are the anchors quoted in issue 6 (`experiments/sop-anchors.csv`), not "
        "measured here."
    )
    L.append("")
    L.append("## Machine and run conditions")
    L.append("")
    for k, v in machine.items():
        L.append(f"- {k}: {v}")
    L.append(
        "- Caveat: budgets are wall clock, so what a run finds depends on the machine's load "
        "(see the load lines above); times at 10^6 cells are memory-bound and vary from run "
        "to run."
    )
    L.append("")

    targets = []  # (target, measured, met)
    sop_found = False
    summary_rows = []
    for plan in SOP_PLANS:
        p = os.path.join(args.results, plan, "results.csv")
        if not os.path.exists(p):
            continue
        sop_found = True
        recs = summarize(load(p))
        by_solver = OrderedDict()
        for r in recs:
            by_solver.setdefault(r["solver"], []).append(r)
        for sid, rs in by_solver.items():
            st = solver_stats(rs)
            runs = max(r["runs"] for r in rs)
            summary_rows.append((plan, sid, rs[0]["budget"], runs, st))
    if sop_found:
        L.append("## TSPLIB SOP (41 instances): summary vs the anchors")
        L.append("")
        L.append(
            "Gap = (median cost over the runs − best known) / best known. "
            "\"at best known\" counts instances whose median reaches the best known value. "
            "Lower bound (harness column `lower_bound`) = the larger of the solver's own bound and "
            "the best-known value when `bks.csv` marks it proven optimal (literature); certified "
            "gap = median cost over that bound; \"proven\" = our solver proved optimality in this run."
        )
        L.append("")
        hdr = "| solver | plan | budget | runs per instance | instances | mean gap | at best known | worst (gap) |"
        names = [k for k in ["prob.100", "rbg358a", "rbg378a", "rbg341a", "rbg323a"] if k in lkh]
        hdr += "".join(f" {k} |" for k in names)
        L.append(hdr)
        L.append("|" + "---|" * (8 + len(names)))
        for peer, a in anchors.items():
            row = (
                f"| {peer} (issue 6 anchor) | – | 10 s | 1 | 41 | {pct(a.get('mean_gap_pct'), 3)} | "
                f"{fmt(a.get('at_bks'))}/41 | – |"
            )
            row += "".join(f" {pct(a.get(k))} |" for k in names)
            L.append(row)
        for plan, sid, budget, runs, st in summary_rows:
            w = st["worst"][:3]
            ws = ", ".join(f"{r['instance']} {pct(r['gap'])}" for r in w if r["gap"] > EPS) or "none"
            row = (
                f"| **{sid}** (ours) | {plan} | {budget} | {runs} | {st['with_bks']} | "
                f"{pct(st['mean'], 3)} | {st['at']}/{st['with_bks']} | {ws} |"
            )
            gi = {r["instance"]: r["gap"] for r in st["worst"]}
            row += "".join(f" {pct(gi.get(k))} |" for k in names)
            L.append(row)
        L.append("")
        # issue-6 targets for the default solver
        for plan, sid, budget, runs, st in summary_rows:
            if sid != "auto":
                continue
            proto = "(issue protocol: median of 5 seeds)" if runs >= 5 else f"({'median of ' + str(runs) + ' seeds' if runs > 1 else '1 seed'} only; the issue asks for the median of 5)"
            if st["count"] != 41:
                proto += f" [only {st['count']} of 41 instances in the results]"
            if "seconds=10" in budget:
                targets.append(
                    (f"10 s: mean gap ≤ 0.10 % {proto}", pct(st["mean"], 3), st["mean"] is not None and st["mean"] <= 0.10 + EPS)
                )
                targets.append((f"10 s: best known on ≥ 38/41 {proto}", f"{st['at']}/{st['with_bks']}", st["at"] >= 38))
                if lkh:
                    listed = {k: v for k, v in lkh.items() if k not in ("mean_gap_pct", "at_bks")}
                    floor = min(listed.values())
                    worse = []
                    for r in st["worst"]:
                        g = r["gap"]
                        if g is None:
                            continue
                        if r["instance"] in listed and g > listed[r["instance"]] + EPS:
                            worse.append(f"{r['instance']} {pct(g)} (LKH-3 {pct(listed[r['instance']])})")
                        elif r["instance"] not in listed and g > floor + EPS:
                            # LKH-3's other instances are at most its smallest listed gap
                            worse.append(f"{r['instance']} {pct(g)} (LKH-3 ≤ {pct(floor)})")
                    targets.append(
                        (
                            f"10 s: no instance worse than LKH-3's figure {proto}",
                            "; ".join(worse) if worse else "none worse",
                            not worse,
                        )
                    )
            if "seconds=1" in budget and "seconds=10" not in budget:
                targets.append((f"1 s: mean gap ≤ 0.5 % {proto}", pct(st["mean"], 3), st["mean"] is not None and st["mean"] <= 0.5 + EPS))

    if sop_found:
        multi = [(plan, [(sid, st) for pl, sid, _, _, st in summary_rows if pl == plan]) for plan in SOP_PLANS]
        multi = [(plan, ss) for plan, ss in multi if len(ss) > 1 and any(sid == "auto" for sid, _ in ss)]
        if multi:
            for plan, ss in multi:
                best = min(ss, key=lambda x: x[1]["mean"] if x[1]["mean"] is not None else 1e300)
                targets.append(
                    (
                        f"default solver `auto` is the strongest (plan {plan}, by mean gap)",
                        ", ".join(f"{sid} {pct(st['mean'], 3)}" for sid, st in ss),
                        best[0] == "auto",
                    )
                )
        else:
            targets.append(("default solver `auto` is the strongest", "not measured (only `auto` was run)", False))

    for plan in SOP_PLANS:
        p = os.path.join(args.results, plan, "results.csv")
        if not os.path.exists(p):
            continue
        recs = summarize(load(p))
        by_solver = OrderedDict()
        for r in recs:
            by_solver.setdefault(r["solver"], []).append(r)
        for sid, rs in by_solver.items():
            L.append(f"### TSPLIB SOP per instance: `{sid}`, plan `{plan}` ({rs[0]['budget']})")
            L.append("")
            instance_table(L, rs)
            L.append("")

    for plan in PCG_PLANS:
        p = os.path.join(args.results, plan, "results.csv")
        if not os.path.exists(p):
            continue
        recs = summarize(load(p))
        by_solver = OrderedDict()
        for r in recs:
            by_solver.setdefault(r["solver"], []).append(r)
        for sid, rs in by_solver.items():
            st = solver_stats(rs)
            runs = max(r["runs"] for r in rs)
            L.append(f"## PCGTSPLIB ({st['count']} instances): `{sid}`, plan `{plan}` ({rs[0]['budget']}, {runs} run(s) per instance)")
            L.append("")
            ws = ", ".join(f"{r['instance']} {pct(r['gap'])}" for r in st["worst"][:5] if r["gap"] > EPS) or "none"
            L.append(
                f"Mean gap to bks.csv {pct(st['mean'], 3)}; at or below the best known on "
                f"{st['at']}/{st['with_bks']} (strictly below on {st['below']}); worst: {ws}."
            )
            L.append("")
            instance_table(L, rs)
            L.append("")
            targets.append(
                (
                    f"PCGTSPLIB: at or below bks on every instance (plan {plan}, {rs[0]['budget']}, {runs} run(s))",
                    f"{st['at']}/{st['with_bks']}",
                    st["at"] == st["with_bks"] and st["with_bks"] > 0,
                )
            )

    def gen_kv(gp):
        return dict(x.split("=", 1) for x in gp.split(";") if "=" in x)

    def short(gp):
        kv = gen_kv(gp)
        return ", ".join(f"{k}={kv[k]}" for k in ("preds", "reversible", "lift") if k in kv)

    p = os.path.join(args.results, "scale", "results.csv")
    if os.path.exists(p):
        rows = load(p)
        recs = summarize(rows)
        greedy = {r["instance"]: r for r in recs if r["solver"] == "greedy"}
        L.append("## Scale (`uniform`, reversible open cells, objective air length, plan `scale`)")
        L.append("")
        L.append(
            "Wall time = the harness column `wall_elapsed_s` of the trial. A budget overrun (wall "
            "time well above the budget) means the solver's set-up before its first budget check "
            "took that long."
        )
        L.append("")
        L.append("| instance | n | generator parameters | solver | budget | air length (mm) | ratio to greedy | wall time (s) |")
        L.append("|---|---|---|---|---|---|---|---|")
        for r in recs:
            grec = greedy.get(r["instance"])
            g = grec["air"] if grec else None
            ratio = r["air"] / g if (g and r["air"] is not None) else None
            L.append(
                f"| {r['instance']} | {r['n']} | {short(r['gen_params'])} | {r['solver']} | {r['budget']} | "
                f"{'–' if r['air'] is None else format(r['air'], '.0f')} | "
                f"{'–' if ratio is None else f'{ratio:.3f}'} | {r['time']:.2f} |"
                + (f" {'; '.join(r['errors'])}" if r["errors"] else "")
            )
            if r["solver"] == "greedy" and r["n"] == "100000":
                targets.append((f"greedy < 1 s at 10^5 ({short(r['gen_params'])})", f"{r['time']:.2f} s", r["time"] < 1.0))
            if r["solver"] == "local-search" and r["n"] == "100000" and ratio is not None:
                measured = f"{ratio:.3f} in {r['time']:.2f} s"
                lift = float(gen_kv(r["gen_params"]).get("lift", "0"))
                if lift > 0 and r["lifts"] is not None and grec and grec["lifts"] is not None:
                    # every lift pays 2 * lift of retract and plunge; with link distance 0 only
                    # coincident points link, so these lifts are the same for every order
                    vert, gvert = r["lifts"] * 2 * lift, grec["lifts"] * 2 * lift
                    planar = (r["air"] - vert) / (g - gvert) if g > gvert else None
                    floor = min(vert, gvert) / g
                    need = (0.80 * g - gvert) / (g - gvert) if g > gvert else None
                    reach = (
                        "so no order reaches 0.80"
                        if floor > 0.80
                        else f"so 0.80 needs planar travel at {need:.3f} × greedy's"
                    )
                    measured += (
                        f" (the {int(r['lifts'])} lifts' retract and plunge, {2 * lift:g} mm each, are "
                        f"{floor:.3f} × greedy's air, {reach}; the planar travel is "
                        f"{planar:.3f} × greedy's)"
                    )
                targets.append(
                    (
                        f"improvement solver (`local-search`) ≤ 0.80 × greedy air at 10^5 in ≤ 10 s ({short(r['gen_params'])})",
                        measured,
                        ratio <= 0.80 and r["time"] <= 10.5,
                    )
                )
        L.append("")
    p = os.path.join(args.results, "scale-1e6.csv")
    if os.path.exists(p):
        rows = load(p)
        L.append(f"## Scale: one process per run with peak memory (`examples/scale.rs`, `{rdir}/scale-1e6.csv`)")
        L.append("")
        L.append("| n | preds | lift | solver | params | budget (s) | air (mm) | greedy air (mm) | ratio | wall time after generation (s) | `solvers::run` time incl. check (s) | peak RSS (MiB) |")
        L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            air, ga = float(r["air"]), float(r["greedy_air"])
            L.append(
                f"| {r['n']} | {r['preds']} | {r.get('lift') or '7'} | {r['solver']} | {r['params']} | {r['seconds'] or 'none'} | "
                f"{air:.0f} | {ga:.0f} | {air / ga:.3f} | {float(r['elapsed_s']):.2f} | "
                f"{float(r['solver_s']):.2f} | {float(r['peak_rss_mib']):.0f} |"
            )
            # a run capped at 60 s is the search cut at the budget, not one finished pass
            if r["n"] == "1000000" and r["solver"] == "local-search" and not r["seconds"]:
                t, m = float(r["solver_s"]), float(r["peak_rss_mib"])
                targets.append(
                    (
                        f"10^6: greedy + one improvement pass (that improves) within 60 s and 4 GiB (preds={r['preds']}, lift={r.get('lift') or '7'}, {r['solver']} {r['params']}, cap {r['seconds'] or 'none'} s)",
                        f"{t:.1f} s incl. check, {m:.0f} MiB, air {air / ga:.3f} × greedy's",
                        t <= 60 and m <= 4096 and air < ga,
                    )
                )
        L.append("")

    if targets:
        T = ["## Issue 6 targets: met or not (as measured here)", ""]
        T.append("| target | measured | met |")
        T.append("|---|---|---|")
        for t, m, ok in targets:
            met = "yes" if ok else ("not measured" if m.startswith("not measured") else "**no**")
            T.append(f"| {t} | {m} | {met} |")
        T.append("")
        i = L.index("## Machine and run conditions")
        L[i:i] = T

    safe_files.write_text(out, "\n".join(L).rstrip() + "\n")
    print(f"wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()

#!/usr/bin/env bash
# Records what a user sees from a cellseq binary, so that a behaviour-preserving change can be
# checked byte for byte against the commit before it:
#
#   scripts/golden-outputs.sh OUTDIR [BINARY] [REFDIR]
#
# BINARY defaults to target/release/cellseq. Written under OUTDIR:
#   generate/   `cellseq generate` of every generator at a few seeds and parameters
#   solve/      `solve --json --max-evals` on TSPLIB SOP and PCGTSPLIB files (elapsed_s removed),
#               `info` of PCGTSPLIB files, `import` of G-code programs and drawings
#   errors/     the messages of a few refused plans and instances
#   report/     `cellseq report` of the committed reference results
#   demo/       `cellseq demo --threads 2`: results.nowall.csv and traces.nowall.csv (the files
#               without their wall_* columns)
#   raw-demo/   the demo's results.csv, traces.csv and manifest.json as written (wall times differ)
#   refreport/  `cellseq report` (tables, LaTeX, plots) of REFDIR/raw-demo when REFDIR is given,
#               else of this recording's own demo, so two binaries are compared on identical input
#
# Compare two recordings with `diff -r -x raw-demo OLD NEW` (nothing printed when they agree),
# the second made with OLD as its REFDIR.
set -euo pipefail
OUT=${1:?usage: scripts/golden-outputs.sh OUTDIR [BINARY] [REFDIR]}
B=${2:-target/release/cellseq}
REF=${3:-}
B=$(realpath "$B")
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
rm -rf "$OUT"
mkdir -p "$OUT"/{generate,solve,errors,report,demo}
OUT=$(realpath "$OUT")
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# drop the named columns (prefix match) of a CSV file; quoted fields are handled by python's csv
nowall() {
    python3 - "$1" "$2" <<'EOF'
import csv, sys
src, dst = sys.argv[1], sys.argv[2]
with open(src, newline='') as f, open(dst, 'w', newline='') as g:
    r = csv.reader(f); w = csv.writer(g, lineterminator='\n')
    head = next(r)
    keep = [i for i, h in enumerate(head) if not h.startswith('wall')]
    w.writerow([head[i] for i in keep])
    for row in r:
        w.writerow([row[i] for i in keep if i < len(row)])
EOF
}

# --- generators -------------------------------------------------------------------------
for s in 1 2 3; do
    "$B" generate panel --seed $s -o "$OUT/generate/panel-$s.json"
    "$B" generate panel --param rows=3 --param cols=2 --seed $s -o "$OUT/generate/panel-3x2-$s.json"
    "$B" generate casing --seed $s -o "$OUT/generate/casing-$s.json"
    "$B" generate casing --param regions=4 --seed $s -o "$OUT/generate/casing-r4-$s.json"
    "$B" generate cabin --seed $s -o "$OUT/generate/cabin-$s.json"
    "$B" generate cabin --param features=30 --seed $s -o "$OUT/generate/cabin-30-$s.json"
    "$B" generate uniform --param n=200 --param tools=3 --seed $s -o "$OUT/generate/uniform-$s.json"
    "$B" generate uniform --param n=100 --param lift=0 --seed $s -o "$OUT/generate/uniform-l0-$s.json"
done
"$B" generate panel --param rows=2 --param cols=2 --param tools=crates/cellseq/src/generate/default-tools.toml \
    --seed 4 -o "$OUT/generate/panel-tools.json"

# --- solve, info, import ---------------------------------------------------------------
solve() { # name file solver evals
    "$B" solve "$2" --solver "$3" --max-evals "$4" --seed 2 --json |
        python3 -c 'import json,sys; d=json.load(sys.stdin); d.pop("elapsed_s",None); print(json.dumps(d,sort_keys=True))' \
            >"$OUT/solve/$1-$3.json"
}
for f in ESC07 ESC12 br17.10 p43.1 ft53.1; do
    solve "$f-pcglns" instances/pcgtsplib/$f.pcglns local-search 20000
    "$B" info instances/pcgtsplib/$f.pcglns >"$OUT/solve/$f-pcglns.info"
done
solve ESC25-pcglns instances/pcgtsplib/ESC25.pcglns ils 50000
for f in ESC07 ESC12 ft53.1; do
    solve "$f-sop" instances/tsplib-sop/$f.sop local-search 20000
done
solve ESC12-sop instances/tsplib-sop/ESC12.sop exact 100000000
for g in panel-1 casing-1 cabin-1 uniform-1; do
    solve "$g" "$OUT/generate/$g.json" local-search 20000
done
for p in tests/fixtures/gcode/mill.ngc tests/fixtures/gcode/laser.gcode tests/fixtures/gcode/real/camotics_buildbotics.gcode; do
    "$B" import "$p" -o "$OUT/solve/import-$(basename "$p").json"
done
for p in tests/fixtures/svg/*.svg; do
    "$B" import "$p" -o "$OUT/solve/import-$(basename "$p").json" 2>"$OUT/solve/import-$(basename "$p").err" || true
done 

# --- refusals: the message and the exit code --------------------------------------------
refuse() { # name command...
    local n=$1
    shift
    set +e
    "$@" >"$OUT/errors/$n.out" 2>"$OUT/errors/$n.err"
    echo "exit $?" >>"$OUT/errors/$n.err"
    set -e
    sed -i "s#$TMP#TMP#g" "$OUT/errors/$n.out" "$OUT/errors/$n.err"
}
printf 'NAME: x\nTYPE: PCGLNS\nDIMENSION: 3\n' >"$TMP/short.pcglns"
refuse pcglns-short "$B" info "$TMP/short.pcglns"
head -c 300 instances/pcgtsplib/ESC07.pcglns >"$TMP/cut.pcglns"
refuse pcglns-cut "$B" info "$TMP/cut.pcglns"
printf 'name = "x"\nreplicates = 0\n[budget]\nevaluations = 10\n' >"$TMP/zero.toml"
refuse plan-zero "$B" check "$TMP/zero.toml"
printf 'name = "x"\n[budget]\nevaluations = 10\n[[instances]]\ngenerator = "nope"\n[[solvers]]\nname = "greedy"\n' >"$TMP/gen.toml"
refuse plan-generator "$B" check "$TMP/gen.toml"
printf 'name = "x"\n[budget]\nevaluations = 10\n[[instances]]\nfiles = ["/etc/*"]\n[[solvers]]\nname = "greedy"\n' >"$TMP/abs.toml"
refuse plan-abs "$B" check "$TMP/abs.toml"
printf 'name = "x"\n[budget]\nevaluations = 10\n[[instances]]\ngenerator = "uniform"\ngrid = { n = 10, bogus = 1 }\n[[solvers]]\nname = "greedy"\nparams = { nope = [1] }\n' >"$TMP/param.toml"
refuse plan-param "$B" check "$TMP/param.toml"
refuse generate-param "$B" generate panel --param nope=1 -o "$TMP/x.json"
refuse generate-kind "$B" generate nope -o "$TMP/x.json"
for p in experiments/*.toml; do
    refuse "check-$(basename "$p" .toml)" "$B" check "$p"
done
# the plan checks print a time estimate measured on this machine: keep only the plan's lines
sed -i '/estimate\|calibrat\|per shard\|seconds/d' "$OUT"/errors/check-*.out

# --- report of the committed reference results ------------------------------------------
for r in paper-casing paper-panel; do
    "$B" report results/reference/$r --out "$OUT/report/$r" >/dev/null
done

# --- the demo: a plan run end to end ----------------------------------------------------
"$B" demo --out "$TMP/demo" --threads 2 >/dev/null 2>&1
nowall "$TMP/demo/results.csv" "$OUT/demo/results.nowall.csv"
nowall "$TMP/demo/traces.csv" "$OUT/demo/traces.nowall.csv"
mkdir -p "$OUT/raw-demo"
cp "$TMP/demo/"{results.csv,traces.csv,manifest.json} "$OUT/raw-demo/"

# --- the whole report (tables, LaTeX, plots) of one demo run, byte for byte -------------
# of REFDIR's demo when given (so two binaries are compared on identical input), else of this one
SRC="$OUT/raw-demo"
if [ -n "$REF" ]; then SRC="$REF/raw-demo"; fi
mkdir -p "$TMP/refdemo"
cp "$SRC/"{results.csv,traces.csv,manifest.json} "$TMP/refdemo/"
"$B" report "$TMP/refdemo" --out "$OUT/refreport" >/dev/null
# PDF figures: same pages, but svg2pdf writes their resource dictionaries in hash-map order
(cd "$OUT/refreport/plots" && ls) >"$OUT/refreport/plots.txt"
rm -f "$OUT"/refreport/plots/*.pdf
echo "recorded in $OUT"

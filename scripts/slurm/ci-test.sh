#!/usr/bin/env bash
# End-to-end test of scripts/slurm/ on a real SLURM: starts a throwaway single-node cluster on
# this machine (munged, slurmctld, slurmd; everything under one temporary directory, no system
# file touched), submits a small plan through submit.sh as a 3-shard array job plus the merge
# step, waits for them (bounded), and checks that the merged results equal a local
# `cellseq run` of the same plan in every non-wall column, and that the report was written.
# The daemons are stopped and the directory removed on every exit path.
#
#   sudo bash scripts/slurm/ci-test.sh          # what .ci/run does (as root, after the tests)
#
# Needs root (the daemons run as root, cgroup-free: proctrack/linuxproc, task/none). Installs
# Debian's slurm-wlm (slurmctld, slurmd, munge) and python3 with apt-get when they are missing.
# Environment: CELLSEQ (binary; default target/release/cellseq, built if missing),
# SLURM_TEST_TIMEOUT (seconds to wait for the jobs, default 300), KEEP=1 keeps the directory.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
TIMEOUT=${SLURM_TEST_TIMEOUT:-300}

say() { echo "slurm-test: $*"; }
fail() {
    echo "slurm-test: FAILED: $*" >&2
    exit 1
}

[ "$(id -u)" -eq 0 ] || fail "must run as root (it starts munged, slurmctld and slurmd)"

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
    ! command -v munged >/dev/null || ! command -v sbatch >/dev/null; then
    say "installing Debian's slurm-wlm"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm >/dev/null
fi
if ! command -v python3 >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends python3 >/dev/null
fi

CELLSEQ=${CELLSEQ:-${CARGO_TARGET_DIR:-$ROOT/target}/release/cellseq}
[ -x "$CELLSEQ" ] || cargo build --release --quiet
[ -x "$CELLSEQ" ] || fail "no cellseq binary at $CELLSEQ"
CELLSEQ=$(cd "$(dirname "$CELLSEQ")" && pwd)/$(basename "$CELLSEQ")
export CELLSEQ

T=$(mktemp -d /tmp/cellseq-slurm.XXXXXX)
chmod 755 "$T"
PIDS=()
cleanup() {
    local rc=$?
    set +e
    if [ -n "${SLURM_CONF:-}" ] && [ -f "$T/slurm.conf" ]; then
        scancel --quiet --user=root >/dev/null 2>&1
    fi
    for p in "${PIDS[@]}"; do
        kill "$p" 2>/dev/null
    done
    for p in "${PIDS[@]}"; do
        for _ in $(seq 50); do
            kill -0 "$p" 2>/dev/null || break
            sleep 0.1
        done
        kill -9 "$p" 2>/dev/null
    done
    if [ "$rc" -ne 0 ]; then
        for f in "$T"/log/*.log "$T"/out/slurm-*.out; do
            [ -f "$f" ] && {
                echo "---- $f (last 30 lines)" >&2
                tail -n 30 "$f" >&2
            }
        done
    fi
    if [ "${KEEP:-0}" = 1 ]; then say "kept $T"; else rm -rf "$T"; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

mkdir -p "$T/munge" "$T/log" "$T/state" "$T/spool" "$T/run" "$T/out"
chmod 700 "$T/munge"

# --- munge: a fresh key and a private socket ---
dd if=/dev/urandom of="$T/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$T/munge/munge.key"
SOCK=$T/munge/munge.socket
munged --force --socket="$SOCK" --key-file="$T/munge/munge.key" \
    --pid-file="$T/run/munged.pid" --log-file="$T/log/munged.log" \
    --seed-file="$T/munge/munged.seed" ||
    fail "munged did not start"
PIDS+=("$(cat "$T/run/munged.pid")")
munge --socket="$SOCK" -n | unmunge --socket="$SOCK" >/dev/null || fail "munge round trip"

# --- a minimal cgroup-free slurm.conf for this host (reached at 127.0.0.1, so the host name
# need not resolve) ---
HOST=$(hostname -s 2>/dev/null || hostname)
NODE=$(slurmd -C | head -n 1 | sed -e "s/^NodeName=[^ ]*/NodeName=$HOST/" -e 's/ RealMemory=[0-9]*//')
# free ports near the defaults, so a real cluster on this machine is left alone
port_free() { ! (echo >"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
CTLD_PORT=16817
while ! port_free "$CTLD_PORT"; do CTLD_PORT=$((CTLD_PORT + 2)); done
SLURMD_PORT=$((CTLD_PORT + 1))
while ! port_free "$SLURMD_PORT"; do SLURMD_PORT=$((SLURMD_PORT + 2)); done
cat >"$T/slurm.conf" <<EOF
ClusterName=cellseqci
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$SOCK
CredType=cred/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/run/slurmctld.pid
SlurmdPidFile=$T/run/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
MinJobAge=600
$NODE NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=ci Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$T/slurm.conf

slurmctld -i || fail "slurmctld did not start"
for _ in $(seq 100); do [ -s "$T/run/slurmctld.pid" ] && break; sleep 0.1; done
PIDS+=("$(cat "$T/run/slurmctld.pid")")
slurmd || fail "slurmd did not start"
for _ in $(seq 100); do [ -s "$T/run/slurmd.pid" ] && break; sleep 0.1; done
PIDS+=("$(cat "$T/run/slurmd.pid")")
up=0
for _ in $(seq 60); do
    if sinfo -h -N -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
        up=1
        break
    fi
    sleep 1
done
[ "$up" = 1 ] || fail "node $HOST did not come up: $(sinfo -N 2>&1 | tr '\n' ' ')"
say "cluster up: $(sinfo -h -N -o '%N %T %c CPUs' | head -n 1), $(sinfo -V)"

# --- the plan: 2 instances x 3 solvers x 2 replicates = 12 trials, evaluation budget ---
cat >"$T/plan.toml" <<'EOF'
name = "slurm-ci"
seed = 11
replicates = 2
reference = "greedy"
[budget]
evaluations = 50000
[[instances]]
generator = "uniform"
seeds = [1, 2]
grid = { n = 25, tools = 2, density = 0.05 }
[[solvers]]
name = "greedy"
[[solvers]]
name = "local-search"
[[solvers]]
name = "ils"
EOF

# --- submit through submit.sh and wait for the merge step ---
cd "$T/out"
CPUS_PER_TASK=1 TIME_PER_SHARD=00:10:00 SUBMIT_WAIT=1 \
    timeout "$TIMEOUT" bash "$ROOT/scripts/slurm/submit.sh" "$T/plan.toml" "$T/cluster" 3 ||
    fail "the array job or the merge step failed, or they took more than ${TIMEOUT} s"
cd "$ROOT"

for i in 1 2 3; do
    [ -f "$T/cluster/results.shard-$i-of-3.csv" ] || fail "shard $i wrote no results"
done
[ -f "$T/cluster/results.csv" ] || fail "the merge step wrote no results.csv"
[ -f "$T/cluster/report/report.md" ] || fail "the merge step wrote no report"

# --- the same plan locally, compared without the wall columns ---
"$CELLSEQ" run "$T/plan.toml" --threads 2 --out "$T/local" >/dev/null
python3 - "$T/cluster/results.csv" "$T/local/results.csv" <<'EOF'
import csv, sys
def rows(path):
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        keep = [h for h in r.fieldnames if not h.startswith("wall_")]
        return keep, sorted(tuple(row[h] for h in keep) for row in r)
(hc, a), (hl, b) = rows(sys.argv[1]), rows(sys.argv[2])
if hc != hl:
    sys.exit(f"columns differ: {hc} vs {hl}")
if len(a) != 12 or a != b:
    for x, y in zip(a, b):
        if x != y:
            print("cluster:", x, "\nlocal:  ", y, file=sys.stderr)
            break
    sys.exit(f"merged cluster results ({len(a)} rows) differ from the local run ({len(b)} rows)")
print(f"slurm-test: {len(a)} trials, {len(hc)} non-wall columns: cluster == local")
EOF
say "ok"

#!/usr/bin/env bash
# Run the workflow on a real, one-node SLURM cluster started on this machine and
# check that its results equal those of a local run (or a given results/ tree,
# e.g. the committed one that .ci/run has just reproduced).
#
#   sudo workflow/scripts/slurm_local_cluster.sh [--worktree] [--keep] [--reference=DIR] [TARGET ...]
#
#   --worktree        test the working tree (tracked and untracked files) instead of HEAD
#   --keep            keep the scratch directory (runs, logs, slurm.conf)
#   --reference=DIR   compare with this results/ tree instead of running the workflow locally
#
# What it does (as root):
#   1. installs Debian's slurm-wlm and munge if missing (apt-get update first);
#   2. writes a private slurm.conf (one node with this machine's CPUs and memory
#      from `slurmd -C`, SelectType=select/cons_tres, ProctrackType=proctrack/linuxproc,
#      no accounting, SlurmctldHost=localhost, MinJobAge=600 so that `squeue`
#      still lists finished jobs when the executor asks) at /etc/slurm/slurm.conf
#      (skipped if that file exists already; removed at the end), with state,
#      logs and a private munge key and socket under a scratch directory;
#   3. starts munged, slurmctld and slurmd as root (foreground processes of this
#      script) and waits for the node to be idle;
#   4. copies the repository (HEAD, or the working tree with --worktree) twice into
#      the scratch directory without results/, runs the workflow in one copy with
#      `snakemake --cores N` (local reference) and in the other with
#      `snakemake --profile workflow/profiles/slurm` (every job through sbatch),
#      timing both;
#   5. compares the two results/ trees (workflow/scripts/slurm_compare.py): byte
#      for byte outside results/timings/, the same file names under it;
#   6. stops the daemons it started (trap on EXIT) and removes the scratch
#      directory (kept with --keep, or when a step failed).
#
# TARGETs default to the workflow's default target (`all`: every rules file,
# p1, p2, p4 and the claims table).
# Needs the SLURM executor plugin at the locked versions: pip install -c requirements/pipeline.lock -e ".[slurm]".
# Exit status: 0 results agree; 1 a run failed or the results differ;
# 77 skipped (not root, or slurm-wlm/munge cannot be installed with apt-get).
set -euo pipefail

SKIP=77
say() { printf '[slurm-check] %s\n' "$*"; }
skip() { say "SKIPPED: $*"; exit "$SKIP"; }
die() { say "FAILED: $*"; exit 1; }

ROOT=$(cd "$(dirname "$0")/../.." && pwd)
SOURCE=head
KEEP=0
REFERENCE=""
TARGETS=()
for arg in "$@"; do
  case "$arg" in
    --worktree) SOURCE=worktree ;;
    --keep) KEEP=1 ;;
    --reference=*) REFERENCE=$(cd "${arg#--reference=}" && pwd); REFERENCE_GIVEN=1 ;;
    -h|--help) sed -n '2,36p' "$0"; exit 0 ;;
    -*) die "unknown option $arg" ;;
    *) TARGETS+=("$arg") ;;
  esac
done

# --- 1. packages -------------------------------------------------------------
[ "$(id -u)" = 0 ] || skip "needs root to install and start slurmctld, slurmd and munged"
need=(slurmctld slurmd sbatch squeue sinfo scontrol munged)
missing() { for c in "${need[@]}"; do command -v "$c" >/dev/null 2>&1 || return 0; done; return 1; }
if missing; then
  command -v apt-get >/dev/null 2>&1 || skip "slurm-wlm/munge not installed and no apt-get"
  say "installing slurm-wlm and munge with apt-get"
  if ! { apt-get update -q >/dev/null && DEBIAN_FRONTEND=noninteractive \
         apt-get install -y -q --no-install-recommends slurm-wlm munge >/dev/null; }; then
    skip "apt-get could not install slurm-wlm and munge"
  fi
  missing && skip "slurm-wlm/munge installed but commands missing"
fi
PY=${PYTHON:-python}
"$PY" -c "import snakemake_executor_plugin_slurm" 2>/dev/null \
  || die "the SLURM executor plugin is not installed: pip install -c requirements/pipeline.lock -e \".[slurm]\""
say "$(slurmctld -V 2>/dev/null), $(munged --version 2>&1 | head -1), $("$PY" -m snakemake --version | sed 's/^/snakemake /')"

# --- 2. configuration ----------------------------------------------------------
STATE=$(mktemp -d /tmp/eqrec-slurm.XXXXXX)
chmod 755 "$STATE"
PIDS=()
FAILED=1
CREATED_CONF=0
cleanup() {
  local rc=$?
  for ((i=${#PIDS[@]}-1; i>=0; i--)); do
    kill "${PIDS[i]}" 2>/dev/null || true
  done
  for pid in "${PIDS[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  [ ${#PIDS[@]} -gt 0 ] && say "stopped the daemons it started (pids ${PIDS[*]})"
  [ "$CREATED_CONF" = 1 ] && rm -f /etc/slurm/slurm.conf
  if [ "$KEEP" = 1 ] || [ "$FAILED" = 1 ]; then
    say "scratch directory kept: $STATE"
  else
    rm -rf "$STATE"
  fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

mkdir -p "$STATE"/{etc,munge,ctld,spool,log}
chmod 700 "$STATE/munge"
dd if=/dev/urandom of="$STATE/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$STATE/munge/munge.key"
SOCK="$STATE/munge/munge.sock"
NODE=$(hostname -s)
NODE_LINE=$(slurmd -C | head -1)            # NodeName=<host> CPUs=.. ... RealMemory=..
CPUS=$(sed -n 's/.*CPUs=\([0-9]*\).*/\1/p' <<<"$NODE_LINE")
# The configuration must be at the default path: the executor's job step drops
# SLURM_CONF from the environment of the `srun` it starts inside each job.
export SLURM_CONF=/etc/slurm/slurm.conf
MARK="# written by eqrec workflow/scripts/slurm_local_cluster.sh"
if [ -e "$SLURM_CONF" ] && ! grep -qF "$MARK" "$SLURM_CONF"; then
  FAILED=0
  skip "$SLURM_CONF exists: this machine has its own SLURM configuration, which this check does not touch"
fi
mkdir -p /etc/slurm
CREATED_CONF=1
cat >"$SLURM_CONF" <<EOF
$MARK (removed when it stops)
ClusterName=eqrec-local
SlurmctldHost=localhost
SlurmctldPort=${SLURMCTLD_PORT:-6817}
SlurmdPort=${SLURMD_PORT:-6818}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$SOCK
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
MinJobAge=600
ReturnToService=2
MailProg=/bin/true
$NODE_LINE NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=local Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
say "slurm.conf: $SLURM_CONF (node: $NODE_LINE)"

# --- 3. daemons ------------------------------------------------------------------
munged -F --force --key-file="$STATE/munge/munge.key" --socket="$SOCK" \
  --pid-file="$STATE/munge/munged.pid" --log-file="$STATE/log/munged.log" \
  --seed-file="$STATE/munge/munged.seed" >"$STATE/log/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$SOCK" ] && break; sleep 0.1; done
[ -S "$SOCK" ] || die "munged did not start (log: $STATE/log/munged.log)"
slurmctld -D -f "$SLURM_CONF" >"$STATE/log/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -f "$SLURM_CONF" >"$STATE/log/slurmd.out" 2>&1 &
PIDS+=($!)
state=""
for _ in $(seq 120); do
  state=$(sinfo -h -N -n "$NODE" -o %t 2>/dev/null | head -1 || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
if [ "$state" != idle ]; then
  tail -n 20 "$STATE"/log/slurm*.log >&2 || true
  die "node $NODE is '${state:-unreachable}', not idle, after 60 s"
fi
say "cluster up: node $NODE idle ($CPUS CPUs), munged/slurmctld/slurmd pids ${PIDS[*]}"

# --- 4. the two runs ---------------------------------------------------------------
# Both runs start from one snapshot of the source, taken once (HEAD's commit, or the
# working tree), so that a commit or an edit made while the local run goes on cannot
# make the two runs differ.
SNAPSHOT="$STATE/source.tar"
if ! git -C "$ROOT" rev-parse --git-dir >/dev/null 2>&1; then  # not a git checkout: the tree
  tar -C "$ROOT" --exclude=./.venv --exclude=./results --exclude=./.snakemake --exclude=./intermediate \
    -cf "$SNAPSHOT" .
elif [ "$SOURCE" = head ]; then
  HEAD_SHA=$(git -C "$ROOT" rev-parse HEAD)
  git -C "$ROOT" archive -o "$SNAPSHOT" "$HEAD_SHA"
  say "source: commit $HEAD_SHA"
else
  (cd "$ROOT" && git ls-files -z --cached --others --exclude-standard \
    | tar --null --ignore-failed-read -T - -cf "$SNAPSHOT" 2>/dev/null)
fi
copy_repo() {  # copy_repo DEST: the snapshot without results, logs, .snakemake, intermediate chunks
  mkdir -p "$1"
  tar -x -C "$1" -f "$SNAPSHOT"
  rm -rf "$1/results" "$1/logs" "$1/resolved" "$1/.snakemake" "$1/intermediate"
}
run() {  # run NAME SNAKEMAKE-ARGS...: run the workflow in $STATE/NAME, set SECONDS_<NAME>
  local name=$1; shift
  local dir="$STATE/$name" t0 t1
  copy_repo "$dir"
  say "$name run: snakemake $* ${TARGETS[*]:-} (in $dir, source: $SOURCE)"
  t0=$(date +%s%N)
  if ! (cd "$dir" && PYTHONPATH="$dir/src${PYTHONPATH:+:$PYTHONPATH}" \
        "$PY" -m snakemake "$@" ${TARGETS[@]+"${TARGETS[@]}"} >"$STATE/log/$name.log" 2>&1); then
    tail -n 40 "$STATE/log/$name.log" >&2
    if [ "$name" = slurm ]; then
      find "$dir/.snakemake/slurm_logs" -name '*.log' -exec tail -n 20 {} + >&2 2>/dev/null || true
      tail -n 20 "$STATE/log/slurmctld.log" >&2 || true
    fi
    die "$name run failed (log: $STATE/log/$name.log)"
  fi
  t1=$(date +%s%N)
  printf -v "SECONDS_$name" '%d.%d' $(((t1 - t0) / 1000000000)) $(((t1 - t0) / 100000000 % 10))
  local var="SECONDS_$name"
  say "$name run done in ${!var} s ($(grep -c '^Finished jobid' "$STATE/log/$name.log") jobs)"
}
if [ -n "$REFERENCE" ]; then
  say "local run skipped: comparing with $REFERENCE"
  SECONDS_local="(not run)"
else
  run local --cores "$CPUS"
  REFERENCE="$STATE/local/results"
fi
run slurm --profile workflow/profiles/slurm
SUBMITTED=$(grep -c "has been submitted with SLURM jobid" "$STATE/log/slurm.log" || true)
[ "$SUBMITTED" -gt 0 ] || die "no job of the SLURM run went through sbatch"
say "SLURM run: $SUBMITTED jobs submitted with sbatch"

# --- 5. compare ----------------------------------------------------------------------
SUBSET=()  # a given reference may hold targets outside this run (e.g. the committed p3_scale table)
if [ -n "${REFERENCE_GIVEN:-}" ]; then SUBSET=(--subset); fi
"$PY" "$ROOT/workflow/scripts/slurm_compare.py" "$REFERENCE" "$STATE/slurm/results" ${SUBSET[@]+"${SUBSET[@]}"} \
  || die "the SLURM run's results differ from the local run's"
FAILED=0
say "PASSED: SLURM results equal the local results; local ${SECONDS_local} s, SLURM ${SECONDS_slurm} s"

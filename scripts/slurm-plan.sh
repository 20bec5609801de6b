#!/usr/bin/env bash
# Proves `sweeptin plan` / `run` / `merge` on a real Slurm: starts a throw-away single-node Slurm
# on this machine (munged + slurmctld + slurmd, no systemd, no cgroups, no accounting), cuts a DEM
# job on the IGN pair into tiles, runs them as a Slurm job array (`sbatch --wait --array=0-(N-1)`),
# merges the mosaic and compares every cell with one `sweeptin dem` run over the same area.
# Prints PASS (exit 0) or FAIL (exit 1), the timings and the versions; stops every daemon it
# started on exit (normal end, error or Ctrl-C).
#
# Needs root (to install packages and to run the daemons as root). Debian/Ubuntu: installs
# slurm-wlm, munge and gdal-bin with apt-get when they are missing.
#
# Environment (all optional):
#   WORK=/tmp/sweeptin-slurm   work dir: slurm.conf, daemon state and logs, plan, tiles, mosaics
#   SWEEPTIN=path              the sweeptin binary (default: `cargo build --release`, then
#                              target/release/sweeptin); copied into $WORK so a rebuild while the
#                              job runs does not change it
#   SWEEPTIN_DATA=../shared/data   where lidar/ign_test_semis_2023_*.laz are
#   TILE=500 CELL=1            the plan's tile side and the DEM cell
#   SLURMCTLD_PORT=6817 SLURMD_PORT=6818   ports of the private Slurm
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD

WORK=${WORK:-/tmp/sweeptin-slurm}
DATA=${SWEEPTIN_DATA:-../shared/data}
TILE=${TILE:-500}
CELL=${CELL:-1}
CTLD_PORT=${SLURMCTLD_PORT:-6817}
SLURMD_PORT=${SLURMD_PORT:-6818}
FILES=("$DATA"/lidar/ign_test_semis_2023_0299_6802_LA93_IGN69.laz
       "$DATA"/lidar/ign_test_semis_2023_0300_6802_LA93_IGN69.laz)
for f in "${FILES[@]}"; do [[ -f $f ]] || { echo "missing input $f" >&2; exit 2; }; done
FILES=("$(realpath "${FILES[0]}")" "$(realpath "${FILES[1]}")")   # the job runs elsewhere

log() { printf '== %s\n' "$*" >&2; }
now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }

# ---------------------------------------------------------------- 1. packages
need=()
command -v slurmctld >/dev/null || need+=(slurmctld)
command -v slurmd >/dev/null || need+=(slurmd)
command -v sbatch >/dev/null || need+=(slurm-client)
command -v munged >/dev/null || need+=(munge)
command -v gdal_translate >/dev/null || need+=(gdal-bin)
if ((${#need[@]})); then
    [[ $(id -u) == 0 ]] || { echo "missing ${need[*]} and not root: install slurm-wlm munge gdal-bin" >&2; exit 2; }
    if ((${#need[@]} >= 3)); then need=(slurm-wlm munge gdal-bin); fi   # the metapackage
    log "installing ${need[*]}"
    # No init system here: keep apt's postinst scripts from starting munge/slurm services that
    # nobody would stop (policy-rc.d exit 101 = "do not start"). Only if there is none already.
    made_policy=
    if [[ ! -e /usr/sbin/policy-rc.d ]]; then
        printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d && chmod +x /usr/sbin/policy-rc.d
        made_policy=1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q --no-install-recommends "${need[@]}" >/dev/null ||
        { apt-get update -q >/dev/null && apt-get install -y -q --no-install-recommends "${need[@]}" >/dev/null; }
    if [[ -n $made_policy ]]; then rm -f /usr/sbin/policy-rc.d; fi
fi
[[ $(id -u) == 0 ]] || { echo "run as root: the private slurmctld/slurmd run as root" >&2; exit 2; }

# ---------------------------------------------------------------- binary and work dir
mkdir -p "$WORK"
WORK=$(realpath "$WORK")
# Only the sub-directories this script owns are removed: a fresh plan dir matters, since a stale
# tiles/task_<i>.json would pass the per-task check below.
rm -rf "${WORK:?}/slurm" "${WORK:?}/job" "${WORK:?}/logs" "${WORK:?}/out" "${WORK:?}/bin"
mkdir -p "$WORK/slurm/state" "$WORK/slurm/spool" "$WORK/slurm/log" "$WORK/logs" "$WORK/out" "$WORK/bin"
if [[ -z ${SWEEPTIN:-} ]]; then
    cargo build --release --quiet --bin sweeptin
    SWEEPTIN=$REPO/target/release/sweeptin
fi
cp "$SWEEPTIN" "$WORK/bin/sweeptin"
BIN=$WORK/bin/sweeptin

# ---------------------------------------------------------------- cleanup (trap)
# Everything started below is recorded here and stopped on exit, in reverse order: first our
# jobs (scancel, so that no slurmstepd outlives slurmd), then slurmd, slurmctld, munged.
PIDS=()        # "name:pid", in start order
JOBID=
stop_pid() { # name pid: SIGTERM, wait up to 20 s, then SIGKILL
    local name=$1 pid=$2 i
    kill -0 "$pid" 2>/dev/null || return 0
    kill -TERM "$pid" 2>/dev/null || true
    for i in $(seq 1 40); do kill -0 "$pid" 2>/dev/null || { log "stopped $name ($pid)"; return 0; }; sleep 0.5; done
    log "$name ($pid) still running after 20 s: SIGKILL"
    kill -KILL "$pid" 2>/dev/null || true
}
cleanup() {
    local rc=$? i
    trap - EXIT INT TERM
    # The cluster is private (our slurmctld, our slurm.conf): any job left on it is ours.
    if [[ -n ${SLURM_CONF:-} ]] && squeue -h 2>/dev/null | grep -q .; then
        log "cancelling the jobs left (${JOBID:-job id not known yet})"
        scancel --user=root 2>/dev/null || true
        for i in $(seq 1 30); do squeue -h 2>/dev/null | grep -q . || break; sleep 1; done
    fi
    for ((i = ${#PIDS[@]} - 1; i >= 0; i--)); do stop_pid "${PIDS[i]%%:*}" "${PIDS[i]#*:}"; done
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ---------------------------------------------------------------- 2. munge
# Slurm authenticates every RPC with munge. Reuse a munged that already answers; otherwise make
# the key if there is none (owner munge, mode 0400) and start munged as the munge user.
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    log "munged already running: reusing it"
else
    if [[ ! -s /etc/munge/munge.key ]]; then
        log "creating /etc/munge/munge.key"
        mkdir -p /etc/munge
        if command -v mungekey >/dev/null; then mungekey --create --keyfile /etc/munge/munge.key --force
        else dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none; fi
    fi
    chown munge:munge /etc/munge/munge.key && chmod 0400 /etc/munge/munge.key
    mkdir -p /run/munge /var/lib/munge /var/log/munge
    chown munge:munge /run/munge /var/lib/munge /var/log/munge
    chmod 0755 /run/munge
    # setpriv execs (no forking wrapper) and --foreground keeps munged from daemonizing, so $!
    # is munged itself, and the trap can stop exactly it.
    setpriv --reuid=munge --regid=munge --init-groups munged --foreground >"$WORK/slurm/log/munged.out" 2>&1 &
    PIDS+=("munged:$!")
    for i in $(seq 1 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.2; done
    munge -n | unmunge >/dev/null || { echo "munged does not answer; see $WORK/slurm/log/munged.out" >&2; exit 2; }
    log "munged started"
fi

# ---------------------------------------------------------------- 2. slurm.conf, daemons
NODE=$(hostname -s)
CPUS=$(nproc)
MEM_TOTAL=$(free -m | awk '/^Mem:/ { print $2 }')
REALMEM=$((MEM_TOTAL * 90 / 100))   # below what slurmd measures, or the node drains (Low RealMemory)
export SLURM_CONF=$WORK/slurm/slurm.conf   # every Slurm command (and the job) reads this one
for port in "$CTLD_PORT" "$SLURMD_PORT"; do
    if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
        echo "port $port is in use (another Slurm?): set SLURMCTLD_PORT/SLURMD_PORT" >&2; exit 2
    fi
done
cat >"$SLURM_CONF" <<EOF
# Written by scripts/slurm-plan.sh: a throw-away single-node Slurm, everything under $WORK/slurm.
ClusterName=sweeptin
SlurmctldHost=$NODE
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$WORK/slurm/state
SlurmdSpoolDir=$WORK/slurm/spool
SlurmctldPidFile=$WORK/slurm/slurmctld.pid
SlurmdPidFile=$WORK/slurm/slurmd.pid
SlurmctldLogFile=$WORK/slurm/log/slurmctld.log
SlurmdLogFile=$WORK/slurm/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups, no MPI, no accounting: works in a container.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MailProg=/bin/true
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
ReturnToService=2
# Keep finished jobs' records 10 minutes, so that scontrol can still report every array task.
MinJobAge=600
InactiveLimit=0
KillWait=30
Waittime=0
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$REALMEM State=UNKNOWN
PartitionName=local Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
log "slurm.conf: node $NODE, $CPUS CPUs, RealMemory=$REALMEM MB -> $SLURM_CONF"

# -D: stay in the foreground, so $! is the daemon; -i (slurmctld): ignore any saved state.
slurmctld -D -i >"$WORK/slurm/log/slurmctld.out" 2>&1 &
PIDS+=("slurmctld:$!")
for i in $(seq 1 60); do scontrol ping 2>/dev/null | grep -q UP && break; sleep 0.5; done
scontrol ping | grep -q UP || { echo "slurmctld is not up; see $WORK/slurm/log/slurmctld.{out,log}" >&2; exit 2; }
slurmd -D >"$WORK/slurm/log/slurmd.out" 2>&1 &
PIDS+=("slurmd:$!")
state=
for i in $(seq 1 60); do
    state=$(sinfo -h -n "$NODE" -o %t 2>/dev/null || true)
    case $state in
        idle) break ;;
        drain* | down* | drng*) scontrol update nodename="$NODE" state=resume 2>/dev/null || true ;;
    esac
    sleep 1
done
[[ $state == idle ]] || {
    echo "node $NODE is '$state', not idle; see $WORK/slurm/log/slurmd.{out,log}" >&2
    scontrol show node "$NODE" >&2 || true
    exit 2
}
log "node $NODE idle"
sinfo

# ---------------------------------------------------------------- 3. plan and job array
PLAN=$WORK/job/plan.json
"$BIN" plan dem "${FILES[@]}" --cell "$CELL" --tile "$TILE" -o "$WORK/job"
N=$(python3 -c 'import json, sys; print(len(json.load(open(sys.argv[1]))["tiles"]))' "$PLAN")
log "$N tasks"

# The job script a user would write (docs/SCALING.md), with this plan's numbers.
cat >"$WORK/dem.sbatch" <<EOF
#!/bin/bash
#SBATCH --job-name=sweeptin-dem
#SBATCH --array=0-$((N - 1))
#SBATCH --cpus-per-task=1
#SBATCH --mem=1G
#SBATCH --output=$WORK/logs/%a.out
# SLURM_ARRAY_TASK_ID picks the task; --resume skips a task whose record already exists.
exec "$BIN" run "$PLAN" --resume --quiet --threads "\${SLURM_CPUS_PER_TASK:-1}"
EOF
# sbatch --wait returns when every array task has ended, with the highest exit status of them.
# It runs in the background only so that the job id (printed at submission) is known at once.
t0=$(now)
sbatch --parsable --wait "$WORK/dem.sbatch" >"$WORK/logs/sbatch.out" 2>"$WORK/logs/sbatch.err" &
sbatch_pid=$!
for i in $(seq 1 100); do [[ -s $WORK/logs/sbatch.out ]] && break; sleep 0.1; done
JOBID=$(head -1 "$WORK/logs/sbatch.out" 2>/dev/null || true)
JOBID=${JOBID%%;*}
log "submitted job array ${JOBID:-?} (0-$((N - 1))), waiting"
sbatch_rc=0
wait "$sbatch_pid" || sbatch_rc=$?
t1=$(now)
JOBID=$(head -1 "$WORK/logs/sbatch.out")
JOBID=${JOBID%%;*}
ARRAY_WALL=$(secs "$t0" "$t1")
log "job $JOBID: sbatch --wait exit $sbatch_rc after $ARRAY_WALL s"
cat "$WORK/logs/sbatch.err" >&2

# Every array task: its Slurm record (while MinJobAge keeps it), its log, its task record.
bad=0
span=$(scontrol -o show job "$JOBID" 2>/dev/null | python3 -c '
import sys, datetime
starts, ends, states = [], [], []
for line in sys.stdin:
    kv = dict(f.split("=", 1) for f in line.split() if "=" in f)
    if "ArrayTaskId" not in kv: continue
    p = lambda s: datetime.datetime.strptime(s, "%Y-%m-%dT%H:%M:%S")
    starts.append(p(kv["StartTime"])); ends.append(p(kv["EndTime"]))
    states.append(kv["JobState"] + "/" + kv["ExitCode"])
if starts:
    bad = [s for s in states if s != "COMPLETED/0:0"]
    print(f"{len(states)} {(max(ends) - min(starts)).total_seconds():.0f} {len(bad)}")
') || true
if [[ -n $span ]]; then
    read -r n_rec span_s n_bad <<<"$span"
    log "scontrol: $n_rec array task records, first start to last end ${span_s} s, $n_bad not COMPLETED/0:0"
    ((n_rec == N && n_bad == 0)) || bad=1
else
    span_s="?"
    log "scontrol has no records of job $JOBID (expired?): relying on exit status and task records"
fi
missing=()
for ((i = 0; i < N; i++)); do [[ -s $WORK/job/tiles/task_$i.json ]] || missing+=("$i"); done
if ((sbatch_rc != 0 || ${#missing[@]} || bad)); then
    echo "FAIL: job array: sbatch exit $sbatch_rc, missing task records: ${missing[*]:-none}" >&2
    for i in "${missing[@]}"; do echo "--- task $i log:" >&2; cat "$WORK/logs/$i.out" >&2 || true; done
    exit 1
fi
log "all $N array tasks succeeded"

# ---------------------------------------------------------------- 4. merge, one run, compare
"$BIN" merge "$PLAN" -o "$WORK/out/merged.tif"
BBOX=$(python3 -c '
import json, sys
t = json.load(open(sys.argv[1]))["tiles"]
b = [min(x["bounds"][0] for x in t), min(x["bounds"][1] for x in t),
     max(x["bounds"][2] for x in t), max(x["bounds"][3] for x in t)]
print(",".join(repr(v) for v in b))' "$PLAN")
log "single run over the tiles' union $BBOX"
t2=$(now)
"$BIN" dem "${FILES[@]}" --cell "$CELL" --bbox "$BBOX" --buffer 100000 -o "$WORK/out/single.tif" -q
t3=$(now)
SINGLE_WALL=$(secs "$t2" "$t3")
gdal_translate -q -of AAIGrid "$WORK/out/merged.tif" "$WORK/out/merged.asc"
gdal_translate -q -of AAIGrid "$WORK/out/single.tif" "$WORK/out/single.asc"
head -5 "$WORK/out/merged.asc" | sed 's/^/   merged: /' >&2

# ---------------------------------------------------------------- 5. report
echo
echo "sweeptin:        $("$BIN" --version) (sha256 $(sha256sum "$BIN" | cut -c1-12)), repository HEAD $(git -C "$REPO" rev-parse --short HEAD 2>/dev/null || echo ?)"
echo "slurm:           $(sinfo --version), $(sbatch --version)"
echo "munge:           $(munged --version 2>&1 | head -1)"
echo "gdal:            $(gdal_translate --version)"
echo "node:            $NODE, $CPUS CPUs, RealMemory=$REALMEM MB"
echo "plan:            $N tasks (tiles of $TILE m, cell $CELL m) over ${#FILES[@]} files"
echo "job array:       job $JOBID, --array=0-$((N - 1)) --cpus-per-task=1, sbatch --wait ${ARRAY_WALL} s (first start to last end ${span_s} s)"
# sweeptin's own time in the tasks (their records), against which the array's wall shows
# Slurm's overhead: scheduling passes every few seconds, and sbatch --wait polling the controller.
TASK_S=$(python3 -c '
import json, sys
s = [json.load(open(f"{sys.argv[1]}/task_{i}.json"))["seconds"] for i in range(int(sys.argv[2]))]
print(f"sum {sum(s):.1f} s, longest {max(s):.1f} s")' "$WORK/job/tiles" "$N")
echo "tasks:           sweeptin time in the $N tasks (their records): $TASK_S"
echo "single run:      sweeptin dem --bbox $BBOX, $CPUS threads, ${SINGLE_WALL} s"
if cmp -s "$WORK/out/merged.asc" "$WORK/out/single.asc"; then
    echo "PASS: job-array mosaic == single run, every cell ($(wc -l <"$WORK/out/merged.asc") lines of AAIGrid identical)"
else
    echo "FAIL: job-array mosaic differs from the single run: $(cmp "$WORK/out/merged.asc" "$WORK/out/single.asc" 2>&1 | head -1)"
    exit 1
fi

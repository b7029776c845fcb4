#!/usr/bin/env bash
# A real Slurm run of `lightpath farm slurm` on this machine: installs Debian's slurm-wlm
# and munge, starts a one-node cluster on localhost (slurmctld and slurmd as root from a
# generated slurm.conf: proctrack/linuxproc, task/none, no accounting), renders one frame
# as 4 tasks plus the merge, split by samples and then by tiles, checks each result
# against the single-process render (to float rounding for sample ranges, bit for bit for
# tiles), and stops every daemon it started.
#
#   sudo benches/farm/slurm-local.sh                 # builds target/dist/lightpath
#   LIGHTPATH=path/to/lightpath benches/farm/slurm-local.sh
#
# Environment: LIGHTPATH (binary), WORK (scratch folder, default a new temp dir; kept),
# SCENE (default cornell), RENDER_ARGS (default "--spp 16 --resolution 96x72 --cryptomatte").
set -euo pipefail

if [ "$(id -u)" != 0 ]; then
    echo "run as root: it installs packages and starts slurmctld, slurmd and munged" >&2
    exit 2
fi
here=$(cd "$(dirname "$0")/../.." && pwd)
WORK=${WORK:-$(mktemp -d /tmp/lightpath-slurm.XXXXXX)}
SCENE=${SCENE:-cornell}
RENDER_ARGS=${RENDER_ARGS:---spp 16 --resolution 96x72 --cryptomatte}
mkdir -p "$WORK"
echo "== scratch: $WORK"

if ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    echo "== installing slurm-wlm and munge"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi
if [ -z "${LIGHTPATH:-}" ]; then
    echo "== building lightpath (release)"
    (cd "$here" && cargo build --profile dist -q)
    LIGHTPATH=${CARGO_TARGET_DIR:-$here/target}/release/lightpath
fi
LIGHTPATH=$(realpath "$LIGHTPATH")
"$LIGHTPATH" --version

started=()
stop() {
    set +e
    if [ -n "${SLURM_CONF:-}" ] && command -v scancel >/dev/null; then
        scancel --quiet --user=root 2>/dev/null
    fi
    for pid in "${started[@]}"; do
        kill "$pid" 2>/dev/null
    done
    for pid in "${started[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    done
    echo "== stopped what this script started (${#started[@]} daemons)"
}
trap stop EXIT

# munge: the key the package made (or a new one), the daemon unless one runs already.
if ! pgrep -x munged >/dev/null; then
    [ -s /etc/munge/munge.key ] || mungekey --create --force
    chown munge:munge /etc/munge/munge.key && chmod 600 /etc/munge/munge.key
    install -d -o munge -g munge -m 755 /run/munge
    install -d -o munge -g munge -m 700 /var/lib/munge /var/log/munge
    runuser -u munge -- /usr/sbin/munged --foreground >"$WORK/munged.log" 2>&1 &
    started+=($!)
    for _ in $(seq 50); do [ -S /run/munge/munge.socket.2 ] && break; sleep 0.1; done
fi
munge -n | unmunge >/dev/null && echo "== munge works"

host=$(hostname -s)
cpus=$(nproc)
mkdir -p "$WORK/slurm/state" "$WORK/slurm/spool"
export SLURM_CONF="$WORK/slurm/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=lightpath
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SlurmctldPort=16817
SlurmdPort=16818
StateSaveLocation=$WORK/slurm/state
SlurmdSpoolDir=$WORK/slurm/spool
SlurmctldPidFile=$WORK/slurm/slurmctld.pid
SlurmdPidFile=$WORK/slurm/slurmd.pid
SlurmctldLogFile=$WORK/slurm/slurmctld.log
SlurmdLogFile=$WORK/slurm/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=render Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
/usr/sbin/slurmctld -D -i -f "$SLURM_CONF" >"$WORK/slurm/slurmctld.out" 2>&1 &
started+=($!)
/usr/sbin/slurmd -D -f "$SLURM_CONF" >"$WORK/slurm/slurmd.out" 2>&1 &
started+=($!)
for _ in $(seq 100); do
    sinfo -h -o %t 2>/dev/null | grep -qx idle && break
    sleep 0.2
done
sinfo
sinfo -h -o %t | grep -qx idle || { echo "the node did not come up" >&2; tail "$WORK"/slurm/*.log >&2; exit 1; }

# shellcheck disable=SC2086
"$LIGHTPATH" render "$SCENE" $RENDER_ARGS --quiet -o "$WORK/single.exr"
status=0
for by in samples tiles; do
    echo "== $SCENE as 4 tasks by $by"
    # shellcheck disable=SC2086
    "$LIGHTPATH" farm slurm "$SCENE" --tasks 4 --by "$by" -o "$WORK/$by.exr" $RENDER_ARGS >"$WORK/submit-$by.sh"
    bash "$WORK/submit-$by.sh"
    start=$(date +%s)
    while squeue -h -o %i | grep -q .; do
        if [ $(($(date +%s) - start)) -gt 900 ]; then
            echo "jobs still queued after 15 minutes" >&2
            squeue >&2
            exit 1
        fi
        sleep 1
    done
    echo "-- jobs done after $(($(date +%s) - start)) s; merge log:"
    cat "$WORK/$by.parts/merge.log"
    [ -f "$WORK/$by.exr" ] || { echo "no $WORK/$by.exr: see $WORK/$by.parts/*.log" >&2; exit 1; }
    if [ "$by" = tiles ]; then tolerance=0; else tolerance=1e-6; fi
    if "$LIGHTPATH" diff "$WORK/single.exr" "$WORK/$by.exr" --tolerance "$tolerance"; then
        echo "-- $by: equals the single-process render (tolerance $tolerance)"
    else
        echo "-- $by: DIFFERS from the single-process render" >&2
        status=1
    fi
done
exit $status

#!/usr/bin/env bash
# slurm_test.sh FLUIDSURF_BINARY - a frame sequence on a real Slurm: a single-node cluster on
# localhost from Debian's slurm-wlm and munge (munged, slurmctld and one slurmd, a throw-away
# config, key and state under a temporary folder, free ports), a 12-frame job array of
# `fluidsurf reconstruct --shard slurm --skip-existing --keep-going` with frame 7 corrupt, waited
# for with a bounded timeout. Checks every other frame's mesh (watertight), the failure report
# in frame 7's log, sbatch's exit code, and that a second submission skips the finished frames.
# Stops every daemon it started. Exit code 77 (ctest: skipped) with the reason when Slurm
# cannot run here: not installed, not root (slurmd must be), or the daemons do not come up.
set -u
BIN=$1
skip() { echo "skipped: $*"; exit 77; }
for tool in munged munge slurmctld slurmd sbatch sinfo scancel; do
    command -v $tool >/dev/null || PATH=$PATH:/usr/sbin command -v $tool >/dev/null ||
        skip "$tool not found (Debian's slurm-wlm and munge; tools/scripts/install-deps.sh installs them)"
done
export PATH=$PATH:/usr/sbin
[ "$(id -u)" -eq 0 ] || skip "slurmd must run as root to start jobs"

T=$(mktemp -d /tmp/fluidsurf_slurm_XXXXXX)
chmod 755 "$T"
daemons=()
stop() {
    [ -n "${SLURM_CONF:-}" ] && timeout 5 scancel --quiet --user=root >/dev/null 2>&1
    for pid in "${daemons[@]}"; do kill "$pid" 2>/dev/null; done
    [ -f "$T/munged.pid" ] && kill "$(cat "$T/munged.pid")" 2>/dev/null
    sleep 0.5
    for pid in "${daemons[@]}"; do kill -9 "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; done
    rm -rf "$T"
}
trap stop EXIT
trap 'exit 1' INT TERM # so that a timeout's SIGTERM still stops the daemons
source "$(dirname "$0")/checks.sh"

# --- the cluster -----------------------------------------------------------------------------
host=$(hostname -s)
read -r ctldPort slurmdPort < <(/usr/bin/python3 -c "
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(('127.0.0.1', 0))
print(*[x.getsockname()[1] for x in s])")
mkdir -p "$T/state" "$T/spool" "$T/munge"
head -c 1024 /dev/urandom >"$T/munge.key"
chmod 600 "$T/munge.key"
munged --force --key-file="$T/munge.key" --socket="$T/munge/socket" --log-file="$T/munged.log" \
    --pid-file="$T/munged.pid" --seed-file="$T/munge.seed" 2>"$T/munged.err" ||
    skip "munged does not start: $(tail -1 "$T/munged.err")"
cat >"$T/slurm.conf" <<EOF
ClusterName=fluidsurftest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctldPort
SlurmdPort=$slurmdPort
AuthType=auth/munge
AuthInfo=socket=$T/munge/socket
CredType=cred/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$T/slurm.conf
slurmctld -D -f "$SLURM_CONF" >"$T/slurmctld.out" 2>&1 &
daemons+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$T/slurmd.out" 2>&1 &
daemons+=($!)
# (Addresses are given, not looked up: a fresh root may not resolve its own host name.)
state() { timeout 5 sinfo -h -N -o %t 2>/dev/null; }
deadline=$((SECONDS + 30))
while [ "$(state)" != idle ] && [ $SECONDS -lt $deadline ]; do sleep 0.5; done
[ "$(state)" = idle ] ||
    skip "the node is not idle after 30 s: $(tail -qn1 "$T/slurmctld.log" "$T/slurmd.log" 2>/dev/null | tr '\n' ' ')"
echo "slurm: $(timeout 5 sinfo -V), node $host idle"

# --- the frames and the job array ------------------------------------------------------------
for f in $(seq 12); do
    "$BIN" generate drop --count $((2000 + 100 * f)) -r 0.01 -o "$T/f_$(printf %04d $f).bgeo" >/dev/null
done
head -c 300 "$T/f_0001.bgeo" >"$T/f_0007.bgeo"
cat >"$T/job.sh" <<EOF
#!/bin/bash
exec "$BIN" reconstruct "$T/f_{:04}.bgeo" -r 0.01 -o "$T/m_{:04}.ply" --raw \\
    --shard slurm --skip-existing --keep-going -j 1
EOF
submit() { # submit LOGPREFIX: sbatch --wait of the array, at most 150 s; prints its exit code
    (cd "$T" && timeout 150 sbatch --wait --quiet --array=1-12 -o "$T/$1_%a.log" "$T/job.sh" \
        >"$T/$1.sbatch" 2>&1)
    echo $?
}
rc=$(submit run)
check "sbatch --wait returned within 150 s (exit $rc)" test "$rc" -ne 124
check "sbatch reports the failed task (exit 1, got $rc)" test "$rc" -eq 1
for f in 1 2 3 4 5 6 8 9 10 11 12; do
    m=$T/m_$(printf %04d $f).ply
    check "frame $f: meshed, watertight" bash -c "'$BIN' info '$m' | grep -q 'check .*watertight'"
    check "frame $f: its log says done" grep -q "reconstruct 1 frame: 1 done, 0 skipped, 0 failed" "$T/run_$f.log"
done
check "frame 7: no mesh" test ! -e "$T/m_0007.ply"
check "frame 7: its log names the corrupt file" grep -q "error: $T/f_0007.bgeo: header promises" "$T/run_7.log"
check "frame 7: and lists it as failed" bash -c "grep -A1 '1 frame failed:' '$T/run_7.log' | grep -q 'f_0007.bgeo'"

# --- the same array again: finished frames are skipped -----------------------------------------
before=$(stat -c '%Y %n' "$T"/m_*.ply | md5sum)
rc=$(submit again)
check "second submission: exit 1 again (frame 7, got $rc)" test "$rc" -eq 1
check "second submission: frame 3 skipped" grep -q "0 done, 1 skipped, 0 failed" "$T/again_3.log"
check "second submission: the meshes untouched" test "$(stat -c '%Y %n' "$T"/m_*.ply | md5sum)" = "$before"

echo "slurm tests: $pass passed, $fail failed"
[ $fail -eq 0 ]

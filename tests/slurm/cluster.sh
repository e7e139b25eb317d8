#!/usr/bin/env bash
# A one-node Slurm on localhost for tests/cli/slurm.rs (as root, with Debian's slurm-wlm
# and munge installed):
#
#   cluster.sh start DIR   write DIR/slurm.conf, start munged (unless one answers already),
#                          slurmctld and slurmd, wait until the node takes jobs; prints
#                          `export SLURM_CONF=DIR/slurm.conf` for the client commands
#   cluster.sh stop DIR    stop what `start` started, by the pid files in DIR
#
# Everything lives in DIR (under /var/tmp: config, spool, state, logs, pid files) and on
# ports picked free, so that neither /etc/slurm nor a Slurm already on the machine is
# touched. Every wait has a limit. `start` exits 1 with one line on stderr saying why
# when a daemon does not come up (its log's tail follows).
set -euo pipefail

action=${1:?usage: cluster.sh start|stop DIR}
dir=${2:?usage: cluster.sh start|stop DIR}

# The daemons live in sbin, which a user's PATH may lack.
export PATH="$PATH:/usr/sbin:/sbin"

say() { echo "cluster.sh: $*" >&2; }

# Wait up to $1 seconds for the command after it to succeed.
wait_for() {
    local limit=$1; shift
    local end=$((SECONDS + limit))
    until "$@" >/dev/null 2>&1; do
        if [ "$SECONDS" -ge "$end" ]; then return 1; fi
        sleep 0.2
    done
}

# Stop the daemon whose pid is in file $1 (TERM, then KILL after 10 s).
stop_pid() {
    local file=$1 pid
    [ -s "$file" ] || return 0
    pid=$(cat "$file")
    if kill -0 "$pid" 2>/dev/null; then
        kill -TERM "$pid" 2>/dev/null || true
        if ! wait_for 10 bash -c "! kill -0 $pid"; then kill -KILL "$pid" 2>/dev/null || true; fi
    fi
    rm -f "$file"
}

# A TCP port nobody listens on (asked of the kernel).
free_port() {
    python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])' 2>/dev/null \
        || echo $((20000 + RANDOM % 20000))
}

fail() {
    say "$1"
    for log in "$dir"/log/*.log; do
        [ -f "$log" ] && { echo "--- $log" >&2; tail -n 15 "$log" >&2; }
    done
    exit 1
}

case $action in
start)
    mkdir -p "$dir"/{spool,state,log,run}
    host=$(hostname -s)
    # munge: the key (created if missing), then munged as the munge user unless one answers.
    if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        if [ ! -s /etc/munge/munge.key ]; then mungekey --create >/dev/null 2>&1 || fail "mungekey --create failed"; fi
        chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key
        mkdir -p /run/munge /var/log/munge /var/lib/munge
        chown munge:munge /run/munge /var/log/munge /var/lib/munge
        runuser -u munge -- munged 2>"$dir/log/munged.log" || fail "munged did not start"
        wait_for 10 bash -c "munge -n | unmunge" || fail "munged does not answer"
        # Ours to stop: a copy of its pid file.
        cp /run/munge/munged.pid "$dir/run/munged.pid"
    fi
    ctld_port=$(free_port)
    slurmd_port=$(free_port)
    cat >"$dir/slurm.conf" <<EOF
# Written by tests/slurm/cluster.sh for one test; removed with it.
ClusterName=eyeshelltest
SlurmctldHost=$host
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=5
Waittime=0
NodeName=$host CPUs=2 State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    export SLURM_CONF=$dir/slurm.conf
    # -i: ignore a state left by an earlier cluster (there is none in a fresh DIR anyway).
    slurmctld -f "$SLURM_CONF" -i >"$dir/log/slurmctld.out" 2>&1 || fail "slurmctld did not start"
    wait_for 20 scontrol ping || fail "slurmctld does not answer scontrol ping"
    slurmd -f "$SLURM_CONF" >"$dir/log/slurmd.out" 2>&1 || fail "slurmd did not start"
    # The node takes jobs once it is idle.
    wait_for 30 bash -c "sinfo -h -N -o %t | grep -qx idle" || fail "the node did not become idle"
    echo "export SLURM_CONF=$SLURM_CONF"
    ;;
stop)
    export SLURM_CONF=$dir/slurm.conf
    # Cancel what may still run, then the daemons, then munged if this script started it.
    [ -f "$SLURM_CONF" ] && timeout 10 scancel --full -u root >/dev/null 2>&1 || true
    stop_pid "$dir/run/slurmd.pid"
    stop_pid "$dir/run/slurmctld.pid"
    stop_pid "$dir/run/munged.pid"
    ;;
*)
    say "unknown action $action (start or stop)"
    exit 2
    ;;
esac

#!/usr/bin/env bash
# Brings up a one-machine Slurm cluster for scripts/farm/slurm-render.sh, unless one already
# answers: installs Debian's slurm-wlm and munge when missing, creates the munge key if absent,
# starts munged, writes /etc/slurm/slurm.conf (one node, this host with its real CPUs and memory;
# no cgroups and no accounting, so it also runs in a container), starts slurmctld and slurmd, and
# waits until sinfo shows the node idle. Run again, it only confirms. An existing slurm.conf that
# this script did not write is used as it is.
#
#   scripts/farm/slurm-up.sh            (as root; env SLURM_UP_TIMEOUT: seconds to wait, default 60)
#
# Exits 0 when a node takes jobs. Otherwise prints why (not root, no apt-get, a daemon that
# failed, with the end of its log) and exits 1.
set -euo pipefail

timeout_s=${SLURM_UP_TIMEOUT:-60}
conf=/etc/slurm/slurm.conf
marker="# Written by quadray scripts/farm/slurm-up.sh"
logdir=/var/log/slurm
start_log=$logdir/slurm-up.log  # the daemons' own output before they open their log files

say() { echo "slurm-up: $*"; }
fail() {
    echo "slurm-up: cannot start Slurm: $*" >&2
    exit 1
}
# Prints the last lines of each file given that exists, for a failure message.
tails() {
    local f
    for f in "$@"; do
        if [ -s "$f" ]; then
            echo "--- last lines of $f" >&2
            tail -n 20 "$f" >&2
        fi
    done
}
# A node that takes jobs: the controller answers (asked first: scontrol fails at once where sinfo
# retries for 9 s) and some node is idle, mixed, allocated or completing (a `*` after the state
# means not responding, `drain` and `down` that it takes none).
node_ready() {
    ctld_up && timeout 10 sinfo -h -N -o %T 2>/dev/null | grep -Eqx 'idle|mixed|allocated|completing'
}
ctld_up() { timeout 5 scontrol ping 2>/dev/null | grep -q 'is UP'; }
munge_up() { munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; }
alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }  # a pid file's process runs
# In this script's cluster, slurmd runs: the controller notices a dead slurmd only after
# SlurmdTimeout (300 s) and shows the node idle until then.
own_slurmd_runs() { ! grep -qF "$marker" "$conf" 2>/dev/null || alive /run/slurmd.pid; }
# Waits up to timeout_s seconds for the command given to succeed.
wait_for() {
    local deadline=$((SECONDS + timeout_s))
    until "$@"; do
        [ "$SECONDS" -lt "$deadline" ] || return 1
        sleep 1
    done
}
# Runs daemon $2 (which writes pid file $1 and forks into the background), then waits as wait_for
# for the check $3, but gives up as soon as the daemon has exited.
start_daemon() {
    local pidfile=$1 daemon=$2 check=$3 deadline=$((SECONDS + timeout_s))
    rm -f "$pidfile"
    say "starting $daemon"
    "$daemon" </dev/null >>"$start_log" 2>&1 || return 1
    until "$check"; do
        if [ -s "$pidfile" ] && ! alive "$pidfile"; then return 1; fi
        [ "$SECONDS" -lt "$deadline" ] || return 1
        sleep 1
    done
}

if command -v sinfo >/dev/null 2>&1 && node_ready && own_slurmd_runs; then
    say "already up: $(sinfo -h -N -o '%N %T, %c CPUs, %m MB' | head -n 1) ($(sinfo -V))"
    exit 0
fi

[ "$(id -u)" = 0 ] || fail "not root (installing and starting Slurm's daemons needs root)"
for cmd in sinfo slurmctld slurmd munged; do
    if ! command -v "$cmd" >/dev/null 2>&1; then
        command -v apt-get >/dev/null 2>&1 || fail "$cmd is missing and apt-get is unavailable"
        say "installing slurm-wlm and munge"
        { timeout 900 apt-get update -qq && DEBIAN_FRONTEND=noninteractive timeout 900 apt-get install -y -qq \
            --no-install-recommends slurm-wlm munge >/dev/null; } \
            || fail "apt-get install slurm-wlm munge failed"
        break
    fi
done
mkdir -p "$logdir"

# munge authenticates every Slurm message. Debian's package creates a key; make one if it did not.
key=/etc/munge/munge.key
if [ ! -s "$key" ]; then
    say "creating $key"
    mkdir -p /etc/munge
    if command -v mungekey >/dev/null 2>&1; then
        mungekey --create --keyfile="$key" --force
    else
        dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
    fi
fi
if ! munge_up; then
    # munged runs as the munge user, who must own the key and the socket's directory (/run is
    # empty after a reboot, and no init system creates /run/munge in a container).
    mkdir -p /run/munge /var/lib/munge /var/log/munge
    chown munge:munge "$key" /run/munge /var/lib/munge /var/log/munge
    chmod 0400 "$key"
    chmod 0755 /run/munge
    say "starting munged"
    runuser -u munge -- munged </dev/null >>"$start_log" 2>&1 \
        || { tails "$start_log" /var/log/munge/munged.log; fail "munged did not start"; }
    wait_for munge_up || { tails /var/log/munge/munged.log; fail "munged does not answer"; }
fi

# The configuration: written when absent or when it is this script's own (then rewritten, so it
# follows the machine's CPUs and memory). `slurmd -C` prints the node line Slurm itself detects.
if [ ! -e "$conf" ] || grep -qF "$marker" "$conf"; then
    host=$(hostname -s)
    node=$(slurmd -C | grep '^NodeName=') || fail "slurmd -C printed no node line"
    mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd
    cat >"$conf.tmp" <<EOF
$marker: one node, this machine.
# No cgroups (ProctrackType, TaskPlugin) and no accounting, so it also runs in a container.
ClusterName=quadray
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
# Start a pending task as soon as a CPU frees, not up to 3 s later: small test frames finish in ms.
SchedulerParameters=batch_sched_delay=0
MailProg=/bin/true
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=$logdir/slurmctld.log
SlurmdLogFile=$logdir/slurmd.log
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=main Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
    if cmp -s "$conf.tmp" "$conf"; then
        rm "$conf.tmp"
    else
        mv "$conf.tmp" "$conf"
        say "wrote $conf: $node"
        # A running controller reads it again (and tells slurmd).
        if ctld_up; then scontrol reconfigure || fail "scontrol reconfigure refused $conf"; fi
    fi
else
    say "using the existing $conf (not written by this script)"
fi

if ! ctld_up; then
    start_daemon /run/slurmctld.pid slurmctld ctld_up \
        || { tails "$start_log" "$logdir/slurmctld.log"; fail "slurmctld did not start or does not answer"; }
fi
if ! alive /run/slurmd.pid; then
    start_daemon /run/slurmd.pid slurmd node_ready || alive /run/slurmd.pid \
        || { tails "$start_log" "$logdir/slurmd.log"; fail "slurmd did not start"; }
fi
if ! node_ready; then
    # Not registered yet, or left down or drained by an earlier run: resume it, then wait.
    scontrol update NodeName="$(hostname -s)" State=RESUME >/dev/null 2>&1 || true
    if ! wait_for node_ready; then
        timeout 10 sinfo -N -l >&2 || true
        timeout 10 scontrol show node >&2 || true
        tails "$start_log" "$logdir/slurmctld.log" "$logdir/slurmd.log"
        fail "no node became idle within ${timeout_s} s"
    fi
fi
say "up: $(sinfo -h -N -o '%N %T, %c CPUs, %m MB' | head -n 1) ($(sinfo -V))"

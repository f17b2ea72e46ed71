#!/usr/bin/env bash
# A single-node SLURM cluster on this (Debian) machine, for running scripts/slurm/sweep_array.sh
# end to end: installs Debian's slurm-wlm and munge, creates a munge key, writes a slurm.conf with
# one node (this host, its CPUs and memory as slurmd reports them) and one partition, and starts
# munged, slurmctld and slurmd. Run as root. Idempotent: a second run restarts the daemons.
#
#   sudo scripts/slurm/setup_single_node.sh
#   sinfo            # the node should be "idle"
set -euo pipefail

if [ "$(id -u)" -ne 0 ]; then
    echo "run as root (it installs packages and starts daemons)" >&2
    exit 2
fi

export DEBIAN_FRONTEND=noninteractive
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    apt-get update -q
    apt-get install -y -q --no-install-recommends slurm-wlm munge
fi

# munge: a key readable by the munge user only, its socket directory
if [ ! -s /etc/munge/munge.key ]; then
    if command -v mungekey >/dev/null; then
        mungekey --create --force
    else
        dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null
    fi
fi
chown munge:munge /etc/munge/munge.key
chmod 400 /etc/munge/munge.key
mkdir -p /run/munge /var/log/munge /var/lib/munge
chown munge:munge /run/munge /var/log/munge /var/lib/munge
stop_pidfile() { # stops the daemon recorded in a pid file, if running
    if [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; then
        kill "$(cat "$1")"
        sleep 1
    fi
}
stop_pidfile /run/munge/munged.pid
runuser -u munge -- /usr/sbin/munged
munge -n | unmunge >/dev/null   # fails here if munge does not work

# slurm.conf for one node: the hardware line as slurmd detects it
HOST=$(hostname -s)
NODELINE=$(slurmd -C | head -n 1 | sed "s/^NodeName=[^ ]*/NodeName=$HOST/")
mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
cat > /etc/slurm/slurm.conf <<CONF
# single-node cluster written by scripts/slurm/setup_single_node.sh
ClusterName=gearbif
SlurmctldHost=$HOST
AuthType=auth/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
# no cgroups (containers often lack them): processes tracked through /proc, no task binding
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
$NODELINE State=UNKNOWN
PartitionName=main Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF

# (re)start the controller and the node daemon
stop_pidfile /run/slurmctld.pid
stop_pidfile /run/slurmd.pid
slurmctld
slurmd
for _ in $(seq 1 30); do
    if sinfo -h -o '%T' 2>/dev/null | grep -qE 'idle|mixed|allocated'; then
        break
    fi
    sleep 1
done
scontrol update NodeName="$HOST" State=RESUME 2>/dev/null || true
sinfo

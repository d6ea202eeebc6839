#!/usr/bin/env bash
# A one-node Slurm cluster for one command (tests/mapping/city_test.cc): munged, slurmctld and
# slurmd (Debian's munge and slurm-wlm) started in DIR with a configuration of their own, the
# command run with SLURM_CONF pointing at it, then every job waited for (TIMEOUT s at most) and
# the daemons stopped. Run it in a private network namespace, as root:
#
#   unshare -n tests/mapping/slurm_cluster.sh DIR TIMEOUT COMMAND...
#
# Slurm resolves its hosts with AI_ADDRCONFIG, which wants a non-loopback IPv4 address: a veth
# pair inside the namespace gives it one (10.254.0.1), reaching nothing outside. Exit status: the
# command's, or 3 when the jobs did not end in time, 4 when the cluster did not come up.
set -uo pipefail
dir=$1
timeout_s=$2
shift 2
mkdir -p "$dir/munge" "$dir/state" "$dir/spool"
chmod 700 "$dir" "$dir/munge"
ip link set lo up
ip link add lmslurm0 type veth peer name lmslurm1
ip addr add 10.254.0.1/24 dev lmslurm0
ip link set lmslurm0 up
ip link set lmslurm1 up

stop() {
  for p in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"; do
    [ -f "$p" ] && kill "$(cat "$p")" 2> /dev/null
  done
}
trap stop EXIT

dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$dir/munge/munge.key"
munged --force --socket="$dir/munge/socket" --key-file="$dir/munge/munge.key" --log-file="$dir/munge/munged.log" \
  --pid-file="$dir/munge/munged.pid" --seed-file="$dir/munge/seed" || { echo "slurm_cluster: munged did not start" >&2; exit 4; }
cat > "$dir/slurm.conf" << EOF
ClusterName=lanemaptest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/builtin
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$dir/slurm.conf
slurmctld -f "$SLURM_CONF" && slurmd -f "$SLURM_CONF" -N localhost || { echo "slurm_cluster: slurmctld/slurmd did not start" >&2; exit 4; }
for _ in $(seq 50); do
  sinfo -h -o %T 2> /dev/null | grep -q idle && break
  sleep 0.2
done
sinfo -h -o %T 2> /dev/null | grep -q idle || { echo "slurm_cluster: the node did not come up" >&2; tail -n 20 "$dir"/*.log >&2; exit 4; }

"$@"
rc=$?
deadline=$((SECONDS + timeout_s))
while [ -n "$(squeue -h 2> /dev/null)" ]; do
  if [ $SECONDS -ge $deadline ]; then
    echo "slurm_cluster: jobs still queued after ${timeout_s} s:" >&2
    squeue >&2
    exit 3
  fi
  sleep 0.5
done
exit $rc

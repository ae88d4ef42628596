#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for testing the batch job arrays.
#   scripts/slurm_cluster.sh start DIR   install slurm-wlm and munge from Debian if missing (as
#                                        root), start munged, slurmctld and slurmd with their
#                                        files in DIR, wait until the node is idle, and write
#                                        DIR/env (source it: SLURM_CONF for sbatch / squeue).
#   scripts/slurm_cluster.sh stop DIR    stop the daemons started in DIR, by their process ids.
# Nothing outside DIR is touched (the Debian munge key is read, not changed). Ports are drawn
# from the process id so two clusters on one machine do not collide.
set -euo pipefail
cmd=${1:?usage: slurm_cluster.sh start|stop DIR}
dir=${2:?usage: slurm_cluster.sh start|stop DIR}

stop() {
  for name in slurmd slurmctld munged; do
    if [ -f "$dir/$name.pid.started" ]; then
      pid=$(cat "$dir/$name.pid.started")
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
      rm -f "$dir/$name.pid.started"
    fi
  done
}

if [ "$cmd" = stop ]; then stop; exit 0; fi
[ "$cmd" = start ] || { echo "slurm_cluster.sh: unknown command '$cmd' (start or stop)" >&2; exit 2; }

missing=()
for p in slurm-wlm munge; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "slurm_cluster: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

dir=$(realpath -m "$dir")
rm -rf "$dir"
mkdir -p "$dir/state" "$dir/spool" "$dir/log"
trap 'stop' ERR

# munged with its own socket, pid and log files; the key Debian generated at install.
/usr/sbin/munged --foreground --force --socket="$dir/munge.sock" --key-file=/etc/munge/munge.key \
  --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munged.seed" \
  >"$dir/log/munged.out" 2>&1 &
echo $! >"$dir/munged.pid.started"
for _ in $(seq 50); do [ -S "$dir/munge.sock" ] && break; sleep 0.1; done
[ -S "$dir/munge.sock" ] || { echo "slurm_cluster: munged did not start (see $dir/log/munged.log)" >&2; exit 1; }

host=$(hostname -s)
mem=$(awk '/MemTotal/ {print int($2 / 1024 * 0.8)}' /proc/meminfo)
port=$((20000 + ($$ % 20000) * 2))
cat >"$dir/slurm.conf" <<CONF
ClusterName=papersimtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.sock
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
MinJobAge=600
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"
echo "export SLURM_CONF='$dir/slurm.conf'" >"$dir/env"

/usr/sbin/slurmctld -D -i -f "$SLURM_CONF" >"$dir/log/slurmctld.out" 2>&1 &
echo $! >"$dir/slurmctld.pid.started"
/usr/sbin/slurmd -D -f "$SLURM_CONF" -N "$host" >"$dir/log/slurmd.out" 2>&1 &
echo $! >"$dir/slurmd.pid.started"

for _ in $(seq 120); do
  state=$(sinfo -h -o %T 2>/dev/null | head -1 || true)
  [ "$state" = idle ] && { echo "slurm_cluster: node $host idle (ports $port, $((port + 1)))"; exit 0; }
  sleep 0.5
done
echo "slurm_cluster: the node did not become idle (state '${state:-none}'); logs in $dir/log" >&2
stop
exit 1

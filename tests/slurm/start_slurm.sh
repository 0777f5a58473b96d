#!/usr/bin/env bash
# A one-node Slurm cluster for the tests, from Debian's packages (slurm-wlm, munge, slurmdbd,
# mariadb-server), started as plain daemons: CI containers have no systemd.
#
# Accounting (MariaDB + slurmdbd) is part of it, as on a real cluster: the executor plugin
# asks `sacct` for job states by default and `sacctmgr` for the user's account, and the
# tests read a killed job's final state from `sacct`. (profiles/slurm asks squeue for job
# states instead, see there; the plugin still falls back to sacct when MinJobAge is short.)
#
# Idempotent: daemons already answering are left alone. Needs root. Exits non-zero with one
# line on stderr ("start_slurm: ...") when the cluster cannot be brought up; the tests skip
# with that line. The state lives in $THERMAXIS_SLURM_STATE (default /var/lib/thermaxis-slurm);
# the pid files of the daemons it started are listed in $STATE/started, and
# tests/slurm/stop_slurm.sh stops those and no others.
set -euo pipefail

STATE="${THERMAXIS_SLURM_STATE:-/var/lib/thermaxis-slurm}"
CLUSTER=thermaxis
ACCOUNT=thermaxis
CONF_DIR=/etc/slurm
MARK="# written by thermaxis tests/slurm/start_slurm.sh"
DB_PASS=thermaxis-tests  # a loopback-only MariaDB of a throw-away test cluster

fail() {
    echo "start_slurm: $*" >&2
    exit 1
}

wait_for() {  # wait_for SECONDS DESCRIPTION COMMAND...
    local seconds=$1 what=$2
    shift 2
    for _ in $(seq "$seconds"); do
        if "$@" >/dev/null 2>&1; then return 0; fi
        sleep 1
    done
    fail "$what did not come up within ${seconds}s (logs in $STATE/log)"
}

[ "$(id -u)" = 0 ] || fail "needs root (it starts munged, mariadbd, slurmdbd, slurmctld and slurmd)"
for tool in munged mariadbd slurmdbd slurmctld slurmd sbatch sacct sacctmgr; do
    command -v "$tool" >/dev/null 2>&1 || PATH="$PATH:/usr/sbin" command -v "$tool" >/dev/null 2>&1 \
        || fail "$tool not found; install the Debian packages slurm-wlm munge slurmdbd mariadb-server"
done
export PATH="$PATH:/usr/sbin"

if [ -f "$CONF_DIR/slurm.conf" ] && ! grep -qF "$MARK" "$CONF_DIR/slurm.conf"; then
    fail "$CONF_DIR/slurm.conf exists and was not written by this script; not touching a real cluster"
fi

mkdir -p "$STATE/log" "$STATE/ctld" "$STATE/d" /run/munge /run/mysqld
chown slurm:slurm "$STATE/ctld" "$STATE/log"
chown munge:munge /run/munge
chown mysql:mysql /run/mysqld

# --- munge: authentication between the daemons and the commands
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    if [ ! -s /etc/munge/munge.key ]; then
        dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    fi
    chown munge:munge /etc/munge/munge.key
    chmod 0400 /etc/munge/munge.key
    runuser -u munge -- munged --pid-file=/run/munge/munged.pid
    echo /run/munge/munged.pid >>"$STATE/started"
    wait_for 20 munged sh -c 'munge -n | unmunge'
fi

# --- MariaDB: the accounting database, on the unix socket only
if ! mariadb-admin ping >/dev/null 2>&1; then
    if [ ! -d /var/lib/mysql/mysql ]; then
        mariadb-install-db --user=mysql --datadir=/var/lib/mysql >"$STATE/log/mariadb-install.log" 2>&1
    fi
    nohup mariadbd --user=mysql --skip-networking --socket=/run/mysqld/mysqld.sock \
        --pid-file=/run/mysqld/mysqld.pid >"$STATE/log/mariadb.log" 2>&1 &
    echo /run/mysqld/mysqld.pid >>"$STATE/started"
    wait_for 60 mariadbd mariadb-admin ping
fi
mariadb -e "CREATE USER IF NOT EXISTS 'slurm'@'localhost' IDENTIFIED BY '$DB_PASS';
            GRANT ALL ON slurm_acct_db.* TO 'slurm'@'localhost'; FLUSH PRIVILEGES;"

# --- configuration: this machine as the one node, its CPUs and memory as slurmd sees them
node_line="$(slurmd -C | head -n 1)"
node_name="$(sed -E 's/^NodeName=([^ ]+).*/\1/' <<<"$node_line")"
mkdir -p "$CONF_DIR"
cat >"$CONF_DIR/slurm.conf" <<EOF
$MARK
ClusterName=$CLUSTER
SlurmctldHost=$node_name
SlurmUser=slurm
AuthType=auth/munge
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/d
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
# No cgroups in containers: track processes by parent id, no task confinement.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=10
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=1000
ReturnToService=2
# Finished jobs stay visible to squeue for 10 min, as the plugin's squeue fallback wants.
MinJobAge=600
KillWait=5
MpiDefault=none
$node_line State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
cat >"$CONF_DIR/slurmdbd.conf" <<EOF
$MARK
DbdHost=localhost
SlurmUser=slurm
AuthType=auth/munge
StorageType=accounting_storage/mysql
StorageHost=localhost
StorageUser=slurm
StoragePass=$DB_PASS
StorageLoc=slurm_acct_db
LogFile=$STATE/log/slurmdbd.log
PidFile=$STATE/slurmdbd.pid
EOF
chown slurm:slurm "$CONF_DIR/slurmdbd.conf"
chmod 0600 "$CONF_DIR/slurmdbd.conf"

# --- slurmdbd, then the cluster, account and user it must know before slurmctld registers
if ! sacctmgr -n list cluster >/dev/null 2>&1; then
    slurmdbd
    echo "$STATE/slurmdbd.pid" >>"$STATE/started"
    wait_for 60 slurmdbd sacctmgr -n list cluster
fi
if ! sacctmgr -n -P list cluster format=cluster | grep -qx "$CLUSTER"; then
    sacctmgr -i add cluster "$CLUSTER" >/dev/null
fi
if ! sacctmgr -n -P list account format=account | grep -qx "$ACCOUNT"; then
    sacctmgr -i add account "$ACCOUNT" Cluster="$CLUSTER" Description=tests Organization=tests >/dev/null
fi
if ! sacctmgr -n -P list user format=user | grep -qx root; then
    sacctmgr -i add user root Account="$ACCOUNT" DefaultAccount="$ACCOUNT" >/dev/null
fi

# --- slurmctld and slurmd
if ! scontrol ping 2>/dev/null | grep -q UP; then
    slurmctld
    echo "$STATE/slurmctld.pid" >>"$STATE/started"
    wait_for 60 slurmctld sh -c 'scontrol ping | grep -q UP'
fi
if ! pgrep -F "$STATE/slurmd.pid" slurmd >/dev/null 2>&1; then
    slurmd
    echo "$STATE/slurmd.pid" >>"$STATE/started"
fi
node_ready() {
    local state
    state="$(sinfo -h -n "$node_name" -o %T 2>/dev/null | head -n 1)"
    case "$state" in
        idle | mixed | allocated | completing) return 0 ;;
        drain* | down*) scontrol update NodeName="$node_name" State=RESUME >/dev/null 2>&1 || true ;;
    esac
    return 1
}
wait_for 60 "node $node_name" node_ready

# A job through the whole chain: submission, scheduling, slurmd, accounting.
job="$(sbatch --parsable --account="$ACCOUNT" --wrap true --output=/dev/null)" \
    || fail "sbatch could not submit a test job"
finished() { sacct -n -X -P -j "$job" -o State 2>/dev/null | grep -q COMPLETED; }
wait_for 60 "test job $job (sacct State COMPLETED)" finished
echo "start_slurm: cluster '$CLUSTER' up: node $node_name ($(sinfo -h -n "$node_name" -o '%c CPUs, %m MB')), account $ACCOUNT"

#!/usr/bin/env bash
# Stops the daemons tests/slurm/start_slurm.sh started, by their pid files, newest first.
set -uo pipefail
STATE="${THERMAXIS_SLURM_STATE:-/var/lib/thermaxis-slurm}"
for pidfile in "$STATE/slurmd.pid" "$STATE/slurmctld.pid" "$STATE/slurmdbd.pid" \
    /run/mysqld/mysqld.pid /run/munge/munged.pid; do
    if [ -s "$pidfile" ]; then
        kill "$(cat "$pidfile")" 2>/dev/null && echo "stop_slurm: stopped $(basename "$pidfile" .pid)"
    fi
done

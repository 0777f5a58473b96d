#!/usr/bin/env bash
# Stops the daemons tests/slurm/start_slurm.sh started (the pid files it listed in
# $STATE/started), newest first; daemons it found already running are left alone.
set -uo pipefail
STATE="${THERMAXIS_SLURM_STATE:-/var/lib/thermaxis-slurm}"
[ -s "$STATE/started" ] || exit 0
tac "$STATE/started" | while read -r pidfile; do
    if [ -s "$pidfile" ] && kill "$(cat "$pidfile")" 2>/dev/null; then
        echo "stop_slurm: stopped $(basename "$pidfile" .pid)"
    fi
done
rm -f "$STATE/started"

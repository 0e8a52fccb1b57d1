#!/usr/bin/env bash
# Both scale-out services at once: deploy/services.sh start|stop|status (see postgres.sh and redis.sh).
set -uo pipefail
here="$(dirname "$0")"
rc=0
"$here/postgres.sh" "${1:-}" || rc=$?
"$here/redis.sh" "${1:-}" || rc=$?
exit "$rc"

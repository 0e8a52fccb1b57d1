#!/usr/bin/env bash
# Debian's PostgreSQL for b2d's Dagster instance (runs, events, schedules), on 127.0.0.1 only, with its data
# in the project's folder: deploy/postgres.sh start|stop|status|url
#   data:     ${B2D_SERVICES_DIR:-<repo>/data/services}/postgres/data   (log beside it: postgres/postgres.log)
#   port:     ${B2D_PG_PORT:-5432}; database and user b2d; password generated on first start (postgres/password)
#   options:  ${B2D_PG_OPTIONS:-} more server settings, e.g. "-c fsync=off" for a throwaway test cluster
# PostgreSQL refuses to run as root: as root the server runs as Debian's `postgres` user, which owns the folder.
# start and stop are idempotent; `url` prints the SQLAlchemy URL for B2D_POSTGRES_URL (it holds the password).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
STATE="${B2D_SERVICES_DIR:-$ROOT/data/services}/postgres"
PORT="${B2D_PG_PORT:-5432}"
PG_BIN="${PG_BIN:-$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)}"

die() { echo "postgres.sh: $*" >&2; exit 3; }
[ -n "$PG_BIN" ] && [ -x "$PG_BIN/pg_ctl" ] || die "PostgreSQL's server is not installed (apt-get install postgresql)"
if [ "$(id -u)" = 0 ]; then
  id postgres >/dev/null 2>&1 || die "running as root needs Debian's postgres user (apt-get install postgresql)"
  as_owner() { runuser -u postgres -- "$@"; }
else
  as_owner() { "$@"; }
fi

running() { [ -s "$STATE/data/PG_VERSION" ] && as_owner "$PG_BIN/pg_ctl" status -D "$STATE/data" >/dev/null 2>&1; }
port() { cat "$STATE/port" 2>/dev/null || echo "$PORT"; }
sql() { PGPASSWORD="$(cat "$STATE/password")" "$PG_BIN/psql" -h 127.0.0.1 -p "$(port)" -U b2d -d postgres -qtAc "$1"; }

init() {
  mkdir -p "$STATE"
  [ "$(id -u)" = 0 ] && chown postgres: "$STATE"
  as_owner test -w "$STATE" || die "$STATE is not writable by $(id -un) (as root: by user postgres; check the parent folders' x bits)"
  (umask 077; head -c 24 /dev/urandom | base64 | tr '+/' '-_' >"$STATE/password")
  [ "$(id -u)" = 0 ] && chown postgres: "$STATE/password"
  as_owner "$PG_BIN/initdb" -D "$STATE/data" -U b2d --pwfile="$STATE/password" --auth=scram-sha-256 \
    --encoding=UTF8 --locale=C.UTF-8 >"$STATE/initdb.log" 2>&1 || die "initdb failed; see $STATE/initdb.log"
}

case "${1:-}" in
  start)
    if running; then echo "postgres: already running on 127.0.0.1:$(port), data in $STATE/data" >&2; exit 0; fi
    [ -s "$STATE/data/PG_VERSION" ] || init
    mkdir -p "$STATE/socket"; [ "$(id -u)" = 0 ] && chown postgres: "$STATE/socket"
    echo "$PORT" >"$STATE/port"
    as_owner "$PG_BIN/pg_ctl" start -D "$STATE/data" -w -t 60 -l "$STATE/postgres.log" \
      -o "-c listen_addresses=127.0.0.1 -p $PORT -k $STATE/socket ${B2D_PG_OPTIONS:-}" >/dev/null \
      || die "the server did not start; see $STATE/postgres.log"
    [ "$(sql "SELECT 1 FROM pg_database WHERE datname = 'b2d'")" = 1 ] || sql "CREATE DATABASE b2d"
    echo "postgres: running on 127.0.0.1:$PORT, data in $STATE/data" >&2 ;;
  stop)
    if running; then as_owner "$PG_BIN/pg_ctl" stop -D "$STATE/data" -m fast -w >/dev/null; fi
    echo "postgres: stopped" >&2 ;;
  status)
    if running; then echo "postgres: running on 127.0.0.1:$(port), data in $STATE/data"; else echo "postgres: stopped"; exit 1; fi ;;
  url)
    [ -s "$STATE/password" ] || die "not initialised yet: run deploy/postgres.sh start"
    # the driver named: SQLAlchemy 2.1 reads plain postgresql:// as psycopg 3, dagster-postgres brings psycopg2
    echo "postgresql+psycopg2://b2d:$(cat "$STATE/password")@127.0.0.1:$(port)/b2d" ;;
  *) echo "usage: deploy/postgres.sh start|stop|status|url" >&2; exit 2 ;;
esac

#!/usr/bin/env bash
# Debian's redis-server as the Celery broker and result backend for b2d, on 127.0.0.1 only, with its files
# in the project's folder: deploy/redis.sh start|stop|status|url
#   files: ${B2D_SERVICES_DIR:-<repo>/data/services}/redis (pid file and log; nothing is persisted: a queue only)
#   port:  ${B2D_REDIS_PORT:-6379}
# start and stop are idempotent.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
STATE="${B2D_SERVICES_DIR:-$ROOT/data/services}/redis"
PORT="${B2D_REDIS_PORT:-6379}"

die() { echo "redis.sh: $*" >&2; exit 3; }
command -v redis-server >/dev/null || die "redis-server is not installed (apt-get install redis-server)"

pid() { cat "$STATE/redis.pid" 2>/dev/null || true; }
running() { local p; p="$(pid)"; [ -n "$p" ] && kill -0 "$p" 2>/dev/null; }
port() { cat "$STATE/port" 2>/dev/null || echo "$PORT"; }

case "${1:-}" in
  start)
    if running; then echo "redis: already running on 127.0.0.1:$(port), files in $STATE" >&2; exit 0; fi
    mkdir -p "$STATE"; echo "$PORT" >"$STATE/port"
    redis-server --bind 127.0.0.1 --port "$PORT" --protected-mode yes --dir "$STATE" --daemonize yes \
      --pidfile "$STATE/redis.pid" --logfile "$STATE/redis.log" --save "" --appendonly no \
      || die "redis-server did not start; see $STATE/redis.log"
    for _ in $(seq 100); do
      [ "$(redis-cli -h 127.0.0.1 -p "$PORT" ping 2>/dev/null)" = PONG ] && break; sleep 0.05
    done
    [ "$(redis-cli -h 127.0.0.1 -p "$PORT" ping 2>/dev/null)" = PONG ] || die "no answer on 127.0.0.1:$PORT; see $STATE/redis.log"
    echo "redis: running on 127.0.0.1:$PORT, files in $STATE" >&2 ;;
  stop)
    if running; then
      p="$(pid)"; kill "$p"
      for _ in $(seq 100); do kill -0 "$p" 2>/dev/null || break; sleep 0.05; done
    fi
    echo "redis: stopped" >&2 ;;
  status)
    if running; then echo "redis: running on 127.0.0.1:$(port), files in $STATE"; else echo "redis: stopped"; exit 1; fi ;;
  url) echo "redis://127.0.0.1:$(port)" ;;
  *) echo "usage: deploy/redis.sh start|stop|status|url" >&2; exit 2 ;;
esac

# Sourced by the farm scripts: a scratch dir cleaned on exit, and start_farm NAME [SERVER ARGS],
# which starts a server on a free loopback port and two 1-thread workers, and sets $address and
# $server (the server's pid). Expects $bin.
work="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

start_farm() {
  local name="$1"
  shift
  "$bin/lightfarm-server" --listen 127.0.0.1:0 --data-dir "$work/data" "$@" \
    >"$work/server.out" 2>"$work/server.log" &
  server=$!
  pids+=($server)
  for _ in $(seq 100); do
    grep -q "listening on" "$work/server.out" 2>/dev/null && break
    sleep 0.1
  done
  address="$(sed -n 's/^listening on //p' "$work/server.out")"
  [ -n "$address" ] || { echo "$name: the server did not start" >&2; exit 1; }
  for w in 1 2; do
    "$bin/lightfarm-worker" --server "$address" --threads 1 --cache-dir "$work/cache$w" \
      2>"$work/worker$w.log" &
    pids+=($!)
  done
}

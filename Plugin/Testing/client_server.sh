#!/usr/bin/env bash
# Runs test_plugin_client_server.py: a 2-rank pvserver in the background on a free port, the
# pvpython client against it, then stops the server. Run under an X server (scripts/plugin.sh).
# Usage: client_server.sh PVPYTHON PLUGIN DATA OUTPUT_DIR NAME REFERENCE
set -euo pipefail
pvpython="$1" plugin="$2" data="$3" out="$4" name="$5" reference="$6"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

# A port that is free now (the system picks it).
port="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("localhost", 0))
print(s.getsockname()[1])')"
log="$out/${name}_pvserver.log"
# --timeout: the server ends its session after 5 minutes whatever happens.
timeout 400 mpiexec --allow-run-as-root --oversubscribe -n 2 \
  pvserver --server-port="$port" --timeout=5 >"$log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true' EXIT

for _ in $(seq 120); do
  grep -q "Accepting connection" "$log" && break
  kill -0 "$server" 2>/dev/null || { cat "$log" >&2; echo "pvserver did not start" >&2; exit 1; }
  sleep 0.5
done
grep -q "Accepting connection" "$log" || { echo "pvserver did not start in time" >&2; exit 1; }

timeout 300 "$pvpython" "$here/test_plugin_client_server.py" \
  "$plugin" "$data" "$out" "$name" "$port" "$reference"

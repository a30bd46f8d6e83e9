#!/usr/bin/env bash
# Installs the tests' npm packages (package.json, pinned by package-lock.json)
# into BUILD_DIR/node_clients, never into the source tree. Skips npm when the
# installed lock file is the same as this one.
#   tests/node/install.sh BUILD_DIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dest=${1:?"usage: install.sh BUILD_DIR"}/node_clients
mkdir -p "$dest"
if cmp -s "$here/package-lock.json" "$dest/node_modules/.package-lock.json.installed" 2>/dev/null; then
  echo "node_clients: up to date in $dest"
  exit 0
fi
command -v npm >/dev/null || { echo "install.sh: npm is missing (tools/scripts/setup.sh installs it)" >&2; exit 1; }
cp "$here/package.json" "$here/package-lock.json" "$dest/"
# Retries: the registry may answer slowly on a busy machine.
for attempt in 1 2 3; do
  if (cd "$dest" && npm ci --no-audit --no-fund --loglevel=error); then
    cp "$here/package-lock.json" "$dest/node_modules/.package-lock.json.installed"
    echo "node_clients: installed in $dest"
    exit 0
  fi
  echo "install.sh: npm ci failed (attempt $attempt)" >&2
  sleep $((attempt * 5))
done
exit 1

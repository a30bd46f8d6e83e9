#!/usr/bin/env bash
# Installs the named Debian packages that are not installed yet (nothing when
# all are). Shared by tools/scripts/setup.sh and tools/scripts/fuzz.sh.
#   tools/scripts/install_packages.sh TAG PACKAGE...    (TAG prefixes the messages)
set -euo pipefail
tag=$1
shift
missing=()
for p in "$@"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "$tag: installing ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "$tag: these Debian packages are missing and installing them needs root: ${missing[*]}" >&2
  exit 1
fi
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"

#!/usr/bin/env bash
# Builds the Debian package and runs the installed program as a rig PC would,
# away from the source and build trees (run by tools/test.sh; docs/deployment.md).
#   tools/scripts/package_check.sh [BUILD_DIR]      (default: build)
#
# 1. `cmake --build BUILD --target package` -> BUILD/rigctl_<version>_amd64.deb;
# 2. its control data: the run-time libraries' packages from dpkg-shlibdeps,
#    no -dev package among them, the /etc/rigctl configs as conffiles;
# 3. the package's files at their installed paths without touching the
#    machine: as root, a private mount namespace overlays the unpacked
#    package's /usr and /etc on the system's (what `dpkg -i` would put there,
#    gone when the check ends); without root or overlayfs, from the unpacked
#    tree (`dpkg -x`) instead;
# 4. there, from an empty working folder: `rigctl --version`, the units'
#    paths, and `rigctl run /usr/share/rigctl/config/quarter_car.yaml --fast
#    --duration 2`.
# Everything is written under one temporary folder, removed at the end.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:-$root/build}" && pwd)

"$root/tools/scripts/install_packages.sh" package dpkg-dev  # dpkg-shlibdeps for the package's Depends
rm -f "$build"/rigctl_*.deb
cmake --build "$build" --target package -j2 >"$build/package.log" 2>&1 || { cat "$build/package.log" >&2; exit 1; }
debs=("$build"/rigctl_*_amd64.deb)
[ ${#debs[@]} -eq 1 ] && [ -f "${debs[0]}" ] || { echo "package_check: expected one rigctl_<version>_amd64.deb in $build, found: ${debs[*]}" >&2; exit 1; }
deb=${debs[0]}
echo "package_check: built $(basename "$deb") ($(du -k "$deb" | cut -f1) kB)"

fail() { echo "package_check: $*" >&2; exit 1; }
depends=$(dpkg-deb -f "$deb" Depends)
echo "package_check: Depends: $depends"
for lib in libc6 libstdc++6 liblcm1 libmodbus5 libsystemd0; do  # not libceres3: Debian's CeresTargets names libceres.a
  [[ $depends == *"$lib"* ]] || fail "Depends does not name $lib (is CPACK_DEBIAN_PACKAGE_SHLIBDEPS on?)"
done
[[ $depends != *-dev* ]] || fail "Depends names a -dev package: $depends"
conffiles=$(dpkg-deb --ctrl-tarfile "$deb" | tar -xO ./conffiles)
[[ $conffiles == *"/etc/rigctl/quarter_car.yaml"* ]] || fail "conffiles lacks /etc/rigctl/quarter_car.yaml: $conffiles"

tmp=$(mktemp -d /tmp/rigctl_package_check.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
dpkg -x "$deb" "$tmp/root"
mkdir "$tmp/work"

# The checks, run with the package's files at PREFIX (/ when overlaid).
cat >"$tmp/check.sh" <<'EOF'
set -euo pipefail
prefix=$1
fail() { echo "package_check: $*" >&2; exit 1; }
rigctl=$prefix/usr/bin/rigctl
missing=$(ldd "$rigctl" | grep "not found" || true)
[ -z "$missing" ] || fail "libraries not found: $missing"
version=$("$rigctl" --version)
echo "package_check: $version"
[[ $version =~ ^rigctl\ [0-9]+\.[0-9]+\.[0-9]+\ \(git\ [^\)]+\)$ ]] || fail "unexpected --version: $version"
unit=$prefix/usr/lib/systemd/system/rigctl.service
for line in "ExecStart=/usr/bin/rigctl run --operator" "RIGCTL_CONFIG=/etc/rigctl/quarter_car.yaml" \
            "LoadCredential=operator.key:/etc/rigctl/operator.key"; do
  grep -qF "$line" "$unit" || fail "$unit lacks '$line'"
done
for f in usr/lib/systemd/system/lcm-logger.service etc/rigctl/quarter_car.yaml usr/share/rigctl/config/half_car.yaml \
         usr/share/rigctl/config/pneumatic_rotary.yaml usr/share/doc/rigctl/deployment.md usr/share/doc/rigctl/copyright; do
  [ -f "$prefix/$f" ] || fail "the package lacks /$f"
done
cd "$work"
"$rigctl" run "$prefix/usr/share/rigctl/config/quarter_car.yaml" --fast --duration 2 --log run.lcm --csv run.csv > run.out 2>&1 ||
  { cat run.out >&2; fail "rigctl run of the installed quarter_car.yaml failed"; }
rows=$(($(wc -l < run.csv) - 1))
[ "$rows" -ge 800 ] || fail "the run wrote $rows rows, expected 2 s of 2.5 ms ticks"
echo "package_check: rigctl run $prefix/usr/share/rigctl/config/quarter_car.yaml --fast --duration 2: exit 0, $rows rows"
EOF

overlay() {  # runs "$@" with the package overlaid on /usr and /etc in a private mount namespace
  unshare --mount --propagation private bash -c '
    set -e
    mount -t overlay overlay -o lowerdir="$1/root/usr":/usr /usr
    mount -t overlay overlay -o lowerdir="$1/root/etc":/etc /etc
    shift; "$@"' _ "$tmp" "$@"
}
export work="$tmp/work"
if [ "$(id -u)" -eq 0 ] && overlay true 2>/dev/null; then
  overlay bash "$tmp/check.sh" ""  # installed paths for real: /usr/bin/rigctl, /usr/share/rigctl, /etc/rigctl
else
  echo "package_check: cannot overlay /usr here (not root, or no overlayfs): checking the unpacked tree" >&2
  bash "$tmp/check.sh" "$tmp/root"
fi

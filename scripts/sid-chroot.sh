#!/usr/bin/env bash
# Today's stack in a Debian unstable (sid) chroot: VTK 9.6, ParaView 6.1, PyVista, Python
# 3.14 and Mesa, from Debian's archive, beside the bookworm host and without touching it.
#
# Usage: scripts/sid-chroot.sh [COMMAND [ARGS...]]
#   Makes the chroot, or reuses the one cached on this machine, then runs COMMAND inside it
#   (default: print the versions) in this checkout, which is bind-mounted at the same path.
#   The exit status is COMMAND's.
#
# The chroot lives in MTPT_SID_CHROOT (default /var/cache/mtpt/sid-chroot), outside any
# checkout, so every clone and every CI run on the machine shares it. It is made anew when
# the archive or the suite change, and when the archive's versions of the installed
# packages differ from the installed ones (checked at each use with one `apt-get update`;
# an archive that cannot be reached keeps the chroot as it is); packages added to the list
# below are installed into it. A new chroot is built beside the old one and replaces it
# only once complete, so an interrupted run leaves no half-made chroot behind.
#
# The archive's address is the host's own, read from its apt sources; Debian's unstable
# there is a frozen snapshot whose Release file has expired, so apt runs with
# Acquire::Check-Valid-Until=false. Mounts (/proc, /dev, /sys, the checkout) are made in a
# private mount namespace (unshare), so they vanish with the command whatever happens.
# pip inside reaches PyPI with the host's CA bundle (PIP_CERT and SSL_CERT_FILE point at a
# copy of it).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
root="${MTPT_SID_CHROOT:-/var/cache/mtpt/sid-chroot}"
suite=sid

# Everything the build, the tests, the Python package and the plugin need inside.
packages=(
  build-essential cmake ninja-build pkg-config dpkg-dev # toolchain
  libgtest-dev googletest                               # unit tests
  libvtk9-dev python3-vtk9                              # VTK 9.6 and its Python
  paraview paraview-dev python3-paraview openmpi-bin    # ParaView 6.1, pvpython, MPI pvbatch
  python3-pyvista                                       # PyVista
  python3-dev python3-venv python3-pip python3-pytest   # pip from source, pytest
  xvfb xauth x11-apps                                   # headless OpenGL (Mesa llvmpipe); xwd
  libhwy-dev libcli11-dev                               # SIMD dispatch, argument parsing
  ca-certificates
)

log() { echo "sid-chroot: $*" >&2; }
[ "$(id -u)" -eq 0 ] || { log "needs root (debootstrap, chroot, mount)"; exit 1; }

# The host's Debian archive: the first URI of a deb entry for a Debian suite in its apt
# sources (deb822 .sources files or one-line .list files).
archive() {
  local files=(/etc/apt/sources.list /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list)
  local f uri
  for f in "${files[@]}"; do
    [ -f "$f" ] || continue
    case "$f" in
    *.sources)
      uri="$(awk 'tolower($1) == "uris:" { print $2; exit }' "$f")" ;;
    *)
      uri="$(awk '$1 == "deb" { for (i = 2; i <= NF; ++i) if ($i ~ /^[a-z]+:\/\//) { print $i; exit } }' "$f")" ;;
    esac
    case "$uri" in
    */debian | */debian/) echo "${uri%/}"; return 0 ;;
    esac
  done
  return 1
}
mirror="$(archive)" || { log "no Debian archive found in /etc/apt/sources*"; exit 1; }
base="suite=$suite mirror=$mirror"

apt_options=(-o Acquire::Check-Valid-Until=false -o APT::Install-Recommends=false
  -o Dpkg::Use-Pty=0 -q)

# in_root DIR COMMAND...: COMMAND inside the chroot at DIR, with /proc, /dev, /sys and the
# checkout mounted in a private mount namespace. The environment is a clean one: the host's
# variables name host paths (pip's find-links, a pyenv Python) that do not exist inside.
in_root() {
  local dir="$1"
  shift
  local ca=/etc/ssl/certs/ca-certificates.crt
  [ -f "${SSL_CERT_FILE:-}" ] && ca="$SSL_CERT_FILE"
  mkdir -p "$dir/etc/ssl" "$dir$here"
  [ -f "$ca" ] && cp "$ca" "$dir/etc/ssl/mtpt-host-ca.crt"
  local env_args=(HOME=/root LANG=C.UTF-8 PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
    DEBIAN_FRONTEND=noninteractive MTPT_IN_SID_CHROOT=1)
  if [ -f "$dir/etc/ssl/mtpt-host-ca.crt" ]; then
    env_args+=(PIP_CERT=/etc/ssl/mtpt-host-ca.crt SSL_CERT_FILE=/etc/ssl/mtpt-host-ca.crt
      REQUESTS_CA_BUNDLE=/etc/ssl/mtpt-host-ca.crt)
  fi
  local v
  for v in CI OMP_NUM_THREADS MTPT_SKIP_PLUGIN MTPT_UPDATE_SCREENSHOT http_proxy https_proxy no_proxy \
    HTTP_PROXY HTTPS_PROXY NO_PROXY PIP_INDEX_URL TERM; do
    [ -n "${!v:-}" ] && env_args+=("$v=${!v}")
  done
  # shellcheck disable=SC2016
  unshare --mount --propagation private -- bash -c '
    set -e
    dir="$1"; here="$2"; shift 2
    mount -t proc proc "$dir/proc"
    mount --rbind /dev "$dir/dev"
    mount --rbind /sys "$dir/sys"
    mount --bind "$here" "$dir$here"
    exec chroot "$dir" /usr/bin/env -i "$@"' bash "$dir" "$here" "${env_args[@]}" \
    bash -c 'cd "$0" && exec "$@"' "$here" "$@"
}

# make_root DIR: debootstrap, apt's settings, the packages, the stamp.
make_root() {
  local dir="$1" started
  started=$(date +%s)
  command -v debootstrap >/dev/null || {
    log "installing debootstrap"
    apt-get install -y -qq --no-install-recommends debootstrap >/dev/null ||
      { apt-get update -qq && apt-get install -y -qq --no-install-recommends debootstrap >/dev/null; }
  }
  rm -rf "$dir"
  mkdir -p "$(dirname "$dir")"
  log "debootstrap $suite from $mirror into $dir"
  debootstrap --variant=minbase "$suite" "$dir" "$mirror" >"$dir.log" 2>&1 ||
    { tail -n 20 "$dir.log" >&2; log "debootstrap failed (log: $dir.log)"; return 1; }
  printf 'Acquire::Check-Valid-Until "false";\nAPT::Install-Recommends "false";\n' \
    >"$dir/etc/apt/apt.conf.d/99mtpt"
  log "installing ${#packages[@]} packages"
  in_root "$dir" apt-get "${apt_options[@]}" update >>"$dir.log" 2>&1
  install_packages "$dir" "$dir.log"
  echo "$base" >"$dir/.mtpt-chroot"
  log "made in $(($(date +%s) - started)) s ($(du -sh "$dir" | cut -f1))"
}

# install_packages DIR LOG: the package list, and a stamp of it.
install_packages() {
  local dir="$1" log_file="$2"
  in_root "$dir" apt-get "${apt_options[@]}" install -y "${packages[@]}" >>"$log_file" 2>&1 ||
    { tail -n 20 "$log_file" >&2; log "package installation failed (log: $log_file)"; return 1; }
  in_root "$dir" apt-get clean
  echo "${packages[*]}" >"$dir/.mtpt-packages"
}

# stale DIR: true when the chroot must be made anew.
stale() {
  local dir="$1"
  [ -x "$dir/usr/bin/env" ] || { log "no chroot at $dir"; return 0; }
  [ "$(cat "$dir/.mtpt-chroot" 2>/dev/null)" = "$base" ] ||
    { log "the archive or the suite changed"; return 0; }
  if ! in_root "$dir" timeout 300 apt-get "${apt_options[@]}" update >/dev/null 2>&1; then
    log "archive not reached: the cached chroot is used as it is"
    return 1
  fi
  if [ "$(cat "$dir/.mtpt-packages" 2>/dev/null)" != "${packages[*]}" ]; then
    log "the package list changed: installing it"
    install_packages "$dir" "$dir.log" || return 0
  fi
  local upgrades
  upgrades="$(in_root "$dir" apt-get "${apt_options[@]}" -s dist-upgrade 2>/dev/null | grep -c '^Inst ' || true)"
  if [ "$upgrades" != 0 ]; then
    log "the archive has new versions of $upgrades installed packages"
    return 0
  fi
  return 1
}

# The cache is checked and made under an exclusive lock, and used under a shared one, so
# that no run replaces the chroot while another runs a command in it.
mkdir -p "$(dirname "$root")"
exec 9>"$root.lock"
flock -x -w 3600 9 || { log "the cache stayed locked for an hour (see $root.lock)"; exit 1; }
if stale "$root"; then
  make_root "$root.new"
  rm -rf "$root"
  mv "$root.new" "$root"
else
  log "reusing $root"
fi
flock -s 9

if [ $# -eq 0 ]; then
  set -- sh -c 'for p in libvtk9-dev paraview python3-pyvista python3 libgl1-mesa-dri; do
    dpkg-query -W -f="\${Package} \${Version}\n" "$p"; done'
fi
# The command does not inherit the lock: this script holds it until the command ends, and a
# daemon the command leaves behind (an X server, say) must not keep it.
in_root "$root" "$@" 9>&-

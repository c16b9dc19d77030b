# Debian chroots cached on this machine, made with debootstrap from the host's own Debian
# archive: sourced by scripts/install/sid-chroot.sh (today's stack) and scripts/device/device-kit.sh (the
# bare chroot the device kit's smoke test runs in). Not a program of its own.
#
# The sourcing script sets, before it calls chroot_prepare:
#   chroot_root      the chroot's folder (outside any checkout, so clones and CI runs share it)
#   chroot_suite     the Debian suite (sid, trixie, ...)
#   chroot_packages  an array: the packages installed on top of debootstrap's minbase
#   chroot_binds     an array: host folders bind-mounted at the same path inside
#   chroot_name      how log lines start
#
# A chroot is made anew when the archive or the suite change, and when the archive's
# versions of its installed packages differ from the installed ones (checked at each use with
# one `apt-get update`; an archive that cannot be reached keeps the chroot as it is); packages
# added to the list are installed into it. A new chroot is built beside the old one and
# replaces it only once complete, so an interrupted run leaves no half-made chroot behind.
#
# The archive's address is the host's own, read from its apt sources; Debian's frozen
# suites there have expired Release files, so apt runs with Acquire::Check-Valid-Until=false.
# Mounts (/proc, /dev, /sys, chroot_binds) are made in a private mount namespace (unshare),
# so they vanish with the command whatever happens. pip inside reaches PyPI with the host's
# CA bundle (PIP_CERT and SSL_CERT_FILE point at a copy of it).

chroot_log() { echo "${chroot_name:-chroot}: $*" >&2; }

# chroot_archive: the first URI of a deb entry for a Debian suite in the host's apt sources
# (deb822 .sources files or one-line .list files).
chroot_archive() {
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

chroot_apt_options=(-o Acquire::Check-Valid-Until=false -o APT::Install-Recommends=false
  -o Dpkg::Use-Pty=0 -q)

# chroot_run DIR COMMAND...: COMMAND inside the chroot at DIR, with /proc, /dev, /sys and
# chroot_binds mounted in a private mount namespace. The environment is a clean one: the
# host's variables name host paths (pip's find-links, a pyenv Python) that do not exist
# inside.
chroot_run() {
  local dir="$1"
  shift
  local ca=/etc/ssl/certs/ca-certificates.crt
  [ -f "${SSL_CERT_FILE:-}" ] && ca="$SSL_CERT_FILE"
  mkdir -p "$dir/etc/ssl"
  [ -f "$ca" ] && cp "$ca" "$dir/etc/ssl/mtpt-host-ca.crt"
  local env_args=(HOME=/root LANG=C.UTF-8 PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
    DEBIAN_FRONTEND=noninteractive)
  if [ -f "$dir/etc/ssl/mtpt-host-ca.crt" ]; then
    env_args+=(PIP_CERT=/etc/ssl/mtpt-host-ca.crt SSL_CERT_FILE=/etc/ssl/mtpt-host-ca.crt
      REQUESTS_CA_BUNDLE=/etc/ssl/mtpt-host-ca.crt)
  fi
  local v
  for v in CI OMP_NUM_THREADS MTPT_SKIP_PLUGIN MTPT_UPDATE_SCREENSHOT MTPT_REQUIRE_PYPI http_proxy https_proxy no_proxy \
    HTTP_PROXY HTTPS_PROXY NO_PROXY PIP_INDEX_URL TERM "${chroot_env[@]}"; do
    [ -n "${!v:-}" ] && env_args+=("$v=${!v}")
  done
  local bind
  for bind in "${chroot_binds[@]}"; do
    mkdir -p "$dir$bind"
  done
  # shellcheck disable=SC2016
  unshare --mount --propagation private -- bash -c '
    set -e
    dir="$1"; binds="$2"; shift 2
    mount -t proc proc "$dir/proc"
    mount --rbind /dev "$dir/dev"
    mount --rbind /sys "$dir/sys"
    while IFS= read -r bind; do
      [ -z "$bind" ] || mount --bind "$bind" "$dir$bind"
    done <<<"$binds"
    exec chroot "$dir" /usr/bin/env -i "$@"' bash "$dir" "$(printf '%s\n' "${chroot_binds[@]}")" \
    "${env_args[@]}" bash -c 'cd "$0" && exec "$@"' "${chroot_workdir:-/}" "$@"
}

# chroot_install DIR LOG: the package list, and a stamp of it.
chroot_install() {
  local dir="$1" log_file="$2"
  if [ ${#chroot_packages[@]} -gt 0 ]; then
    chroot_run "$dir" apt-get "${chroot_apt_options[@]}" install -y "${chroot_packages[@]}" >>"$log_file" 2>&1 ||
      { tail -n 20 "$log_file" >&2; chroot_log "package installation failed (log: $log_file)"; return 1; }
  fi
  chroot_run "$dir" apt-get clean
  echo "${chroot_packages[*]}" >"$dir/.mtpt-packages"
}

# chroot_make DIR BASE: debootstrap, apt's settings, the packages, the stamp BASE.
chroot_make() {
  local dir="$1" base="$2" mirror="$3" started
  started=$(date +%s)
  command -v debootstrap >/dev/null || {
    chroot_log "installing debootstrap"
    apt-get install -y -qq --no-install-recommends debootstrap >/dev/null ||
      { apt-get update -qq && apt-get install -y -qq --no-install-recommends debootstrap >/dev/null; }
  }
  rm -rf "$dir"
  mkdir -p "$(dirname "$dir")"
  chroot_log "debootstrap $chroot_suite from $mirror into $dir"
  debootstrap --variant=minbase "$chroot_suite" "$dir" "$mirror" >"$dir.log" 2>&1 ||
    { tail -n 20 "$dir.log" >&2; chroot_log "debootstrap failed (log: $dir.log)"; return 1; }
  printf 'Acquire::Check-Valid-Until "false";\nAPT::Install-Recommends "false";\n' \
    >"$dir/etc/apt/apt.conf.d/99mtpt"
  chroot_log "installing ${#chroot_packages[@]} packages"
  chroot_run "$dir" apt-get "${chroot_apt_options[@]}" update >>"$dir.log" 2>&1
  chroot_install "$dir" "$dir.log"
  echo "$base" >"$dir/.mtpt-chroot"
  chroot_log "made in $(($(date +%s) - started)) s ($(du -sh "$dir" | cut -f1))"
}

# chroot_stale DIR BASE: true when the chroot must be made anew.
chroot_stale() {
  local dir="$1" base="$2"
  [ -x "$dir/usr/bin/env" ] || { chroot_log "no chroot at $dir"; return 0; }
  [ "$(cat "$dir/.mtpt-chroot" 2>/dev/null)" = "$base" ] ||
    { chroot_log "the archive or the suite changed"; return 0; }
  if ! chroot_run "$dir" timeout 300 apt-get "${chroot_apt_options[@]}" update >/dev/null 2>&1; then
    chroot_log "archive not reached: the cached chroot is used as it is"
    return 1
  fi
  if [ "$(cat "$dir/.mtpt-packages" 2>/dev/null)" != "${chroot_packages[*]}" ]; then
    chroot_log "the package list changed: installing it"
    chroot_install "$dir" "$dir.log" || return 0
  fi
  local upgrades
  upgrades="$(chroot_run "$dir" apt-get "${chroot_apt_options[@]}" -s dist-upgrade 2>/dev/null | grep -c '^Inst ' || true)"
  if [ "$upgrades" != 0 ]; then
    chroot_log "the archive has new versions of $upgrades installed packages"
    return 0
  fi
  return 1
}

# chroot_prepare: makes the chroot at chroot_root, or reuses it, and holds a shared lock on
# it through file descriptor 9 until the calling script ends. The cache is checked and made
# under an exclusive lock, and used under a shared one, so that no run replaces the chroot
# while another runs a command in it. Commands run with `chroot_run "$chroot_root" ... 9>&-`:
# a daemon a command leaves behind (an X server, say) must not keep the lock.
chroot_prepare() {
  [ "$(id -u)" -eq 0 ] || { chroot_log "needs root (debootstrap, chroot, mount)"; return 1; }
  local mirror base
  mirror="$(chroot_archive)" || { chroot_log "no Debian archive found in /etc/apt/sources*"; return 1; }
  base="suite=$chroot_suite mirror=$mirror"
  mkdir -p "$(dirname "$chroot_root")"
  exec 9>"$chroot_root.lock"
  flock -x -w 3600 9 || { chroot_log "the cache stayed locked for an hour (see $chroot_root.lock)"; return 1; }
  if chroot_stale "$chroot_root" "$base"; then
    chroot_make "$chroot_root.new" "$base" "$mirror"
    rm -rf "$chroot_root"
    mv "$chroot_root.new" "$chroot_root"
  else
    chroot_log "reusing $chroot_root"
  fi
  flock -s 9
}

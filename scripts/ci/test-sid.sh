#!/usr/bin/env bash
# Today's stack: builds MTPT against Debian unstable's VTK 9.6, runs every test there (the
# Python tests and `pip install` from source included, PyVista's among them), then builds
# the ParaView plugin against ParaView 6.1 and runs its tests: scripts/test.sh --shuffled,
# inside the chroot made or reused by scripts/sid-chroot.sh. The gtest programs run whole,
# their tests in a random order (scripts/ci/shuffled-tests.sh): bookworm's run of
# scripts/test.sh gives each test a process of its own, this one shows that none depends on
# the order or on what another test left.
#
# Usage: scripts/ci/test-sid.sh [build-dir]   (default: build-sid, in this checkout; the
#        plugin's tree is <build-dir>-plugin)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-build-sid}"
case "$build" in
/*) ;;
*) build="$here/$build" ;;
esac
case "$build" in
"$here"/*) ;;
*)
  echo "test-sid: the build tree must lie inside the checkout ($here), which is what the" \
    "chroot sees" >&2
  exit 1
  ;;
esac
started=$(date +%s)
"$here/scripts/install/sid-chroot.sh" | sed 's/^/test-sid: /' # the versions of the stack
"$here/scripts/install/sid-chroot.sh" bash "$here/scripts/test.sh" --shuffled "$build"
echo "test-sid: today's stack built and tested in $(($(date +%s) - started)) s"

#!/usr/bin/env bash
# Installs everything cfa-mitsuba needs on Debian 12 (apt and pip), idempotent.
#   apt: libllvm19 (Mitsuba's LLVM variant needs LLVM >= 16; the project
#        finds the library by itself), chromium (headless report checks).
#   pip: this package with its test extra (pip install -e .[test]), byte-compiled.
set -euo pipefail
cd "$(dirname "$0")"
SUDO=""
if [ "$(id -u)" != 0 ] && command -v sudo >/dev/null; then SUDO=sudo; fi
APT_PACKAGES="libllvm19 chromium"
missing=""
for p in $APT_PACKAGES; do dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"; done
if [ -n "$missing" ]; then
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi
python3 -m pip install -q --disable-pip-version-check -e ".[test]"
# Byte-compile the package: an editable install is not, and where PYTHONDONTWRITEBYTECODE is set (as on
# this project's machines) every command and study worker would compile its modules again (0.3 s each).
python3 -m compileall -q -j 0 cfa_mitsuba >/dev/null
echo "setup.sh: ready ($(python3 -c 'import mitsuba; print("mitsuba", mitsuba.__version__)'))" >&2

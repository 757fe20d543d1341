#!/usr/bin/env bash
# Installs headless Chromium for the browser test of the report
# (tests/test_report_browser.py), where this machine can: root and apt-get
# (Debian package `chromium`). Never fails: without Chromium that test skips,
# and this script says why. Run before the tests, e.g. in .ci/run:
#   bash workflow/scripts/install_chromium.sh
# Set EQREC_CI_BROWSER=0 to skip the install.
set -u
for b in chromium chromium-browser google-chrome google-chrome-stable; do
  if command -v "$b" >/dev/null 2>&1; then
    echo "[ci] browser test: using $(command -v "$b") ($("$b" --version 2>/dev/null | head -n 1))"
    exit 0
  fi
done
if [ -n "${EQREC_CHROMIUM:-}" ] && [ -x "${EQREC_CHROMIUM}" ]; then
  echo "[ci] browser test: using EQREC_CHROMIUM=${EQREC_CHROMIUM}"
  exit 0
fi
if [ "${EQREC_CI_BROWSER:-1}" = 0 ]; then
  echo "[ci] browser test SKIPPED: EQREC_CI_BROWSER=0"
  exit 0
fi
if [ "$(id -u)" != 0 ]; then
  echo "[ci] browser test SKIPPED: chromium not installed and not root (apt-get install chromium needs root)"
  exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "[ci] browser test SKIPPED: chromium not installed and no apt-get to install it"
  exit 0
fi
log="$(mktemp /tmp/eqrec-chromium-install.XXXXXX.log)"
if (apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium) \
    >"$log" 2>&1 && command -v chromium >/dev/null 2>&1; then
  echo "[ci] browser test: installed $(chromium --version 2>/dev/null | head -n 1)"
else
  echo "[ci] browser test SKIPPED: apt-get could not install chromium (log: $log)"
  tail -n 5 "$log" | sed 's/^/[ci]   /'
fi
exit 0

#!/usr/bin/env bash
# System packages the test suite needs that pip cannot provide: Debian's Chromium, which the browser tests
# drive through Playwright (a browser download by Playwright is impossible on the target machines).
set -euo pipefail
if command -v chromium >/dev/null 2>&1; then
    exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        echo "install-system-deps: chromium is missing and this user cannot run apt-get; install Debian's 'chromium' package" >&2
        exit 1
    fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends chromium >/dev/null
command -v chromium >/dev/null

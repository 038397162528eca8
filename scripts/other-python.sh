#!/usr/bin/env bash
# Prints the path of an interpreter of another supported Python than the version given (e.g. 3.11), the
# newest one this machine has (a real pythonX.Y on PATH, or one of pyenv's versions); nothing if it has none.
# `make test` sets up simatch for it too, so that the tests verify recordings across Python versions
# (tests/record/test_divergence.py; docs/reliability.md). The supported versions are those with a lock in
# locks/ (docs/install.md).
set -uo pipefail
this="${1:?usage: other-python.sh X.Y (the version not to print)}"
cd "$(dirname "$0")/.."
versions=$(ls locks/ | sed -n 's/^pylock\.run-py3\([0-9]*\)\.toml$/3.\1/p' | sort -t. -k2,2nr)
for v in $versions; do
    [ "$v" = "$this" ] && continue
    # a real interpreter (pyenv's shims exist for every version but fail for one not selected)
    if python="$(command -v "python$v")" && "$python" -c 'pass' >/dev/null 2>&1; then
        echo "$python"
        exit 0
    fi
    if command -v pyenv >/dev/null 2>&1; then
        for full in $(pyenv versions --bare 2>/dev/null | grep -E "^${v//./\\.}\.[0-9]+$" | sort -t. -k3,3nr); do
            python="$(pyenv root)/versions/$full/bin/python$v"
            if "$python" -c 'pass' >/dev/null 2>&1; then
                echo "$python"
                exit 0
            fi
        done
    fi
done
exit 0

#!/usr/bin/env bash
# Makes the README's screenshots of the web UI again (docs/img/referee-console.png, docs/img/coach-page.png).
# The browser test that draws them in headless chromium (tests/web/test_readme_screenshots.py: a refereed
# match, seed 1, at one minute) writes test-artifacts/web/readme/; this runs it and copies them into docs/img/.
# Run it after a change to the pages; the test suite makes them too but never touches docs/.
set -euo pipefail
cd "$(dirname "$0")/.."
.venv/bin/python -m pytest tests/web/test_readme_screenshots.py -q -k screenshots_of
mkdir -p docs/img
cp test-artifacts/web/readme/referee-console.png test-artifacts/web/readme/coach-page.png docs/img/
ls -l docs/img/referee-console.png docs/img/coach-page.png

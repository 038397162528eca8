#!/usr/bin/env bash
# Makes the README's screenshots of the web UI again (docs/img/referee-console.png, docs/img/coach-page.png,
# docs/img/view3d.png). The browser tests that draw them in headless chromium (tests/web/test_readme_screenshots.py
# and tests/web/test_view3d.py: a refereed match, seed 1, at one minute) write test-artifacts/web/readme/; this
# runs them and copies the pictures into docs/img/.
# Run it after a change to the pages; the test suite makes them too but never touches docs/.
set -euo pipefail
cd "$(dirname "$0")/.."
.venv/bin/python -m pytest tests/web/test_readme_screenshots.py tests/web/test_view3d.py -q -k "screenshots_of or readme_screenshot"
mkdir -p docs/img
cp test-artifacts/web/readme/referee-console.png test-artifacts/web/readme/coach-page.png test-artifacts/web/readme/view3d.png docs/img/
ls -l docs/img/referee-console.png docs/img/coach-page.png docs/img/view3d.png

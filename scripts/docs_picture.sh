#!/usr/bin/env bash
# Makes docs/images/horn-cutaway.png, the picture README.md and docs/report.md show: the horn's
# shell (README's first command) cut away at y, taken from the --html page the tool writes.
# Usage: scripts/docs_picture.sh [BUILD_DIR]   (default: build)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$build/assets/vdb_shell_shapes" horn -o "$work/horn.obj" > /dev/null
"$build/cli/vdb_shell" "$work/horn.obj" -o "$work/horn.vtu" --html "$work/horn.html" -q
mkdir -p "$root/docs/images"
# The page's second picture is the cut-away at y.
python3 - "$work/horn.html" "$root/docs/images/horn-cutaway.png" <<'PY'
import base64, re, sys
pictures = re.findall(r'<img class="pic"[^>]*src="data:image/png;base64,([^"]+)"', open(sys.argv[1]).read())
open(sys.argv[2], "wb").write(base64.b64decode(pictures[1]))
PY
echo "wrote docs/images/horn-cutaway.png"

#!/usr/bin/env bash
# The main job on a self-contained default: installs and builds what is missing, starts a
# surfeledit-server, and runs a scripted editing session on a generated scene, one line per step.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh" >&2
exec "$ROOT/.venv/bin/python" -m surfeledit.demo "$@"

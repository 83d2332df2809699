#!/usr/bin/env bash
# Name collisions between the sources of one target, whatever the unity batches: configures a unity build that
# puts every source of a target in one file (CMAKE_UNITY_BUILD_BATCH_SIZE=0) and compiles each such file with
# -fsyntax-only. The sanitizer builds of scripts/test.sh are unity builds of up to eight sources, so a collision
# there depends on which files share a batch, and adding a file moves the batches; this check does not.
#   bash scripts/unity_check.sh [build dir, default build-unity-check]
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
DIR="${1:-$ROOT/build-unity-check}"
mkdir -p "$DIR"
cmake -S "$ROOT" -B "$DIR" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=0 \
  -DSURFELEDIT_PCH=OFF -DSURFELEDIT_BUILD_PYTHON=OFF -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >"$DIR/unity-check-configure.log" 2>&1 \
  || { echo "configure failed: $DIR/unity-check-configure.log"; exit 1; }
# The service's sources include the IDL's generated header.
cmake --build "$DIR" --target surfeledit_proto_generate >/dev/null 2>&1 || true
python3 - "$DIR" <<'PY'
import json, shlex, subprocess, sys
failed = []
for e in json.load(open(f"{sys.argv[1]}/compile_commands.json")):
    if "/Unity/" not in e["file"] or not e["file"].endswith(".cxx"):
        continue
    args, skip = [], False
    for a in shlex.split(e["command"]):
        if skip:
            skip = False
        elif a in ("-o", "-MF", "-MT"):
            skip = True
        elif a != "-MD":
            args.append(a)
    target = e["file"].split("CMakeFiles/")[1].split(".dir")[0]
    r = subprocess.run(args + ["-fsyntax-only", "-fmax-errors=20"], cwd=e["directory"], capture_output=True, text=True)
    print(f"{target}: {'ok' if r.returncode == 0 else 'FAILED'}", flush=True)
    if r.returncode != 0:
        failed.append(target)
        print("\n".join(l for l in r.stderr.splitlines() if "error" in l or "previously" in l))
sys.exit(1 if failed else 0)
PY

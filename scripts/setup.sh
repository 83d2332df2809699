#!/usr/bin/env bash
# Installs whatever is missing (Debian packages, the .venv Python environment with the
# client and its compiled module) and builds. Idempotent: a second run only rebuilds
# what changed. Run as root on a fresh Debian 12 machine (or with sudo available).
#   SURFELEDIT_BUILD_DIR  build directory (default: build)
#   SURFELEDIT_JOBS       parallel build jobs (default: nproc)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${SURFELEDIT_BUILD_DIR:-$ROOT/build}"
JOBS="${SURFELEDIT_JOBS:-$(nproc)}"
VENV="$ROOT/.venv"
log() { printf '[setup %s s] %s\n' "$SECONDS" "$*"; }

# 1. Debian packages.
APT_PACKAGES=(build-essential cmake git pkg-config python3 python3-venv python3-dev
  libeigen3-dev libpcl-dev cyclonedds-dev cyclonedds-tools
  libgtest-dev libspdlog-dev libcli11-dev libbenchmark-dev libcgal-dev ccache openssl zlib1g-dev
  gdb libboost-dev)  # gdb: scripts/test.sh prints a hung test's stacks with it; Boost: Asio's thread pool
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  log "installing Debian packages: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  # Without the recommended packages (desktop, audio and video stacks PCL and VTK suggest): ~185 fewer packages
  # on a fresh machine; nothing here uses them.
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}" >/tmp/surfeledit-apt.log 2>&1 \
    || { tail -n 30 /tmp/surfeledit-apt.log; exit 1; }
fi

# 2. Python environment (re-installed when scripts/requirements.txt changes).
if [ ! -x "$VENV/bin/python" ]; then
  log "creating $VENV"
  python3 -m venv "$VENV"
fi
stamp="$VENV/.requirements.sha256"
want="$(sha256sum "$ROOT/scripts/requirements.txt" "$ROOT/client_py/pyproject.toml" | sha256sum | cut -d' ' -f1)"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  log "installing Python packages into $VENV"
  "$VENV/bin/pip" install -q --disable-pip-version-check -r "$ROOT/scripts/requirements.txt"
  "$VENV/bin/pip" install -q --disable-pip-version-check --no-deps -e "$ROOT/client_py"
  echo "$want" >"$stamp"
fi

# 2b. .venv-secure: the same client on the cyclonedds 0.10.2 binding, built from source against
# Debian's libddsc (which has the DDS Security plugins; the 11.x wheel has none); the secured Python
# tests (tests/python/security) run in it. SURFELEDIT_SECURE_VENV=0 skips it.
VENV_SECURE="$ROOT/.venv-secure"
if [ "${SURFELEDIT_SECURE_VENV:-1}" != 0 ]; then
  [ -x "$VENV_SECURE/bin/python" ] || { log "creating $VENV_SECURE"; python3 -m venv "$VENV_SECURE"; }
  stamp="$VENV_SECURE/.requirements.sha256"
  want="$(sha256sum "$ROOT/scripts/requirements-secure.txt" "$ROOT/client_py/pyproject.toml" | sha256sum | cut -d' ' -f1)"
  if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    log "installing Python packages into $VENV_SECURE (cyclonedds 0.10.2 built against Debian's libddsc)"
    # The binding's build wants one prefix with include/, lib/ and bin/ (CYCLONEDDS_HOME); Debian
    # splits them, so a prefix of links inside the venv stands in for it.
    home="$VENV_SECURE/cyclonedds-home"
    mkdir -p "$home"
    ln -sfn /usr/include "$home/include"
    ln -sfn "$(pkg-config --variable=libdir CycloneDDS)" "$home/lib"
    ln -sfn /usr/bin "$home/bin"
    # The binding alone without pip's wheel cache: a wheel cached from a build against another
    # prefix would record that prefix's libddsc.
    CYCLONEDDS_HOME="$home" "$VENV_SECURE/bin/pip" install -q --disable-pip-version-check --no-cache-dir \
      --no-binary cyclonedds "$(grep -E '^cyclonedds==' "$ROOT/scripts/requirements-secure.txt")"
    "$VENV_SECURE/bin/pip" install -q --disable-pip-version-check -r "$ROOT/scripts/requirements-secure.txt"
    "$VENV_SECURE/bin/pip" install -q --disable-pip-version-check --no-deps -e "$ROOT/client_py"
    echo "$want" >"$stamp"
  fi
fi

# 3. Build: core library, server, pybind11 module (into client_py/surfeledit), C++ tests, benchmarks.
mkdir -p "$BUILD"
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  log "configuring $BUILD"
  # ccache: rebuilds of another checkout of the same sources (a CI clone, a worktree) hit the cache.
  cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE="$VENV/bin/python" \
    -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache \
    -Dpybind11_DIR="$("$VENV/bin/python" -m pybind11 --cmakedir)" \
    -DSURFELEDIT_BUILD_TESTS=ON -DSURFELEDIT_BUILD_PYTHON=ON -DSURFELEDIT_BUILD_BENCH=ON >"$BUILD/setup-configure.log" 2>&1 \
    || { tail -n 40 "$BUILD/setup-configure.log"; exit 1; }
fi
log "building ($JOBS jobs)"
cmake --build "$BUILD" -j "$JOBS" >"$BUILD/setup-build.log" 2>&1 || { "$ROOT/scripts/build_failed.sh" "$BUILD/setup-build.log" "$BUILD"; exit 1; }

# The client finds the server on PATH inside the venv.
ln -sf "$BUILD/server/app/surfeledit-server" "$VENV/bin/surfeledit-server"
log "ready: $BUILD, $VENV"

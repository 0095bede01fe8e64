#!/usr/bin/env bash
# One entry point for a fresh Debian machine: installs what the project needs
# (idempotent), configures, builds, then runs the main job or the tests.
#   tools/run.sh demo   -> the main job (see README.md)
#   tools/run.sh test   -> the whole test suite (CI calls this)
#   tools/run.sh build  -> set-up and build only
# Environment: KUAVO_BUILD_DIR (default build/), KUAVO_JOBS (default nproc), KUAVO_ARCH
# (-march of every target, default x86-64-v3 = the robot; x86-64-v4 adds the AVX-512 tiles).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${KUAVO_BUILD_DIR:-$here/build}"
jobs="${KUAVO_JOBS:-$(nproc)}"

# chromium + chromium-driver + python3: the HTML report's browser test (tests/report).
# libmujoco-dev: the second simulator (kuavo simulate --engine mujoco).
packages=(build-essential cmake libeigen3-dev libsimbody-dev libsundials-dev libmujoco-dev
          libtinyxml2-dev nlohmann-json3-dev libgtest-dev libgmock-dev libbenchmark-dev
          parallel python3 chromium chromium-driver)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "[run.sh] installing: ${missing[*]}"
  sudo_cmd=""; [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}"
fi

cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release ${KUAVO_ARCH:+-DKUAVO_ARCH="$KUAVO_ARCH"} >/dev/null
cmake --build "$build" -j "$jobs"

case "${1:-build}" in
  build) ;;
  test)
    cd "$build"
    ctest --output-on-failure -j "$jobs" --timeout 1200
    ;;
  demo)
    shift
    "$build/kuavo" demo "$@"
    ;;
  *)
    shift || true
    "$build/kuavo" "$@"
    ;;
esac

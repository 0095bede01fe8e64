#!/usr/bin/env bash
# Runs every benchmark pinned to one core. Usage: tools/bench.sh [filter-regex]
# The AVX-512 build: KUAVO_ARCH=x86-64-v4 KUAVO_BUILD_DIR=build-v4 tools/bench.sh [filter-regex]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/tools/run.sh" build >/dev/null
for b in "${KUAVO_BUILD_DIR:-$here/build}"/bench/*_bench; do
  echo "== $(basename "$b")"
  taskset -c 1 "$b" --benchmark_filter="${1:-.}" --benchmark_min_time=0.5
done

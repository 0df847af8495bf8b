#!/usr/bin/env bash
# The sanitizer job: builds everything with clang under AddressSanitizer, UndefinedBehaviorSanitizer
# and LeakSanitizer, with the libFuzzer targets, in BUILD_DIR (default build-sanitize); runs the
# whole test suite there, where any report fails its test; then runs every fuzz target for
# FUZZ_SECONDS each (scripts/fuzz.sh). Needs the packages of scripts/install-deps.sh.
# Usage: bash scripts/sanitize.sh [BUILD_DIR] [FUZZ_SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-sanitize}
seconds=${2:-15}
# -O1 with line tables: ASan's recommended optimisation, readable stacks, a shorter build.
CXX=clang++ cmake -S . -B "$build" -G Ninja -DVDB_SHELL_FUZZ=ON -DVDB_SHELL_BUILD_BENCHMARKS=OFF \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only"
cmake --build "$build"
export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
# Not install_and_use: it links an outside program against the instrumented library without the
# sanitizer runtime; the normal build runs it.
ctest --test-dir "$build" --output-on-failure -j2 -E '^install_and_use$'
bash scripts/fuzz.sh "$build" "$seconds"

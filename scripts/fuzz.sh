#!/usr/bin/env bash
# Runs every libFuzzer target of tests/fuzz (built with -DVDB_SHELL_FUZZ=ON in BUILD_DIR) for
# SECONDS each, seeded from generated shapes in every format variant, ../shared/meshes, a level
# set and the inputs under tests/fuzz/regressions, and prints each target's executions. A crash,
# sanitizer report, hang (> 10 s an input, 60 s for .vdb) or allocation above 2 GiB fails the
# run; the input is kept in FINDINGS_DIR (default: fuzz-findings/) to be added under
# tests/fuzz/regressions/.
# Usage: bash scripts/fuzz.sh BUILD_DIR [SECONDS] [FINDINGS_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:?usage: scripts/fuzz.sh BUILD_DIR [SECONDS] [FINDINGS_DIR]}")
seconds=${2:-15}
findings=$(realpath -m "${3:-fuzz-findings}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$findings"

# Seeds: small shapes and the tetrahedron in every variant of every format, the smaller shared
# meshes, a level set written by vdb_shell, the regression inputs, and a few command lines.
mkdir -p "$work/seeds"/{obj,off,ply,stl,vdb,cli}
for shape in box sphere torus horn flap; do
  "$build/assets/vdb_shell_shapes" "$shape" -o "$work/seeds/obj/$shape.obj" > /dev/null
done
"${PYTHON:-/usr/bin/python3}" scripts/fuzz_seeds.py "$work/seeds" ../shared/meshes
"$build/cli/vdb_shell" "$work/seeds/obj/box.obj" -o "$work/box.vtu" --resolution 16 \
  --grids "$work/seeds/vdb/box.vdb" -q
for format in obj off ply stl; do
  cp tests/fuzz/regressions/$format/* "$work/seeds/$format/" 2> /dev/null || true
done
printf 'box.obj\n-o\nbox.vtu\n--resolution\n16' > "$work/seeds/cli/run"
printf 'a.obj\nb.off\n-o\nout/\n--format\nmsh\n--msh-version\n2.2' > "$work/seeds/cli/batch"
printf -- '--help' > "$work/seeds/cli/help"
printf 'x.vdb\n--grid\nsurface\n--adaptivity\n0.5\n-o\nx.mesh\n--timeout\n1' > "$work/seeds/cli/vdb"

# The targets use the shared sanitizer runtime, which must come first (libFuzzer's link puts
# libstdc++ ahead of it).
runtime=$(clang++ -print-file-name=libclang_rt.asan-x86_64.so)
status=0
printf '%-8s %12s %10s  %s\n' target executions seconds result
for target in obj off ply stl vdb cli; do
  corpus="$work/corpus_$target"
  mkdir -p "$corpus" "$work/artifacts_$target"
  log="$work/$target.log"
  # A .vdb input is read four ways, each meshing the whole volume: a single active tile 4,096
  # voxels wide (a 9 kB file) is a sound level set of 98,304 quads, which takes the four 31 s
  # under the sanitizers.
  timeout=10
  [ "$target" = vdb ] && timeout=60
  set +e
  (cd "$work" && LD_PRELOAD="$runtime" "$build/tests/fuzz/fuzz_$target" "$corpus" "$work/seeds/$target" \
    -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb=2048 -max_len=200000 \
    -print_final_stats=1 -artifact_prefix="$work/artifacts_$target/" > "$log" 2>&1)
  code=$?
  set -e
  # The .vdb target's reader runs in the program vdb_shell_vdb_reader (vdb_io.cpp), whose crashes
  # are contained and whose reports are discarded: only the target's own exit code counts.
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' ||
    echo 0)
  result=clean
  if [ $code -ne 0 ]; then
    kept=$(ls -t "$work/artifacts_$target" | head -1)
    cp "$work/artifacts_$target/$kept" "$findings/$target-$kept"
    result="FINDING (exit $code): $findings/$target-$kept"
    status=1
    tail -40 "$log" | grep -m3 -E 'ERROR|SUMMARY|Timeout|out-of-memory' >&2 || tail -5 "$log" >&2
  fi
  printf '%-8s %12s %10s  %s\n' "$target" "$runs" "$seconds" "$result"
done
exit $status

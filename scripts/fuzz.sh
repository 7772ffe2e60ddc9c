#!/usr/bin/env bash
# Builds the libFuzzer targets (if needed) and runs each for SECONDS.
#   scripts/fuzz.sh SECONDS [TARGET...]
# TARGET is one of ply_ascii ply_binary xyz off obj stl tree_json (default:
# all, one after the other). Each starts from the seeds in fuzz/corpus/TARGET
# and keeps what it finds in build-fuzz/corpus/TARGET; a crashing, hanging
# (10 s) or leaking input is written to build-fuzz/artifacts/TARGET/. Exits
# non-zero when any target failed. Set CSGVOX_FUZZ_BUILD to use another
# build directory.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${CSGVOX_FUZZ_BUILD:-$root/build-fuzz}
all=(ply_ascii ply_binary xyz off obj stl tree_json)

if [[ $# -lt 1 || ! $1 =~ ^[0-9]+$ ]]; then
  echo "usage: $0 SECONDS [TARGET...]   (targets: ${all[*]})" >&2
  exit 2
fi
seconds=$1
shift
targets=("$@")
[[ ${#targets[@]} -eq 0 ]] && targets=("${all[@]}")
for t in "${targets[@]}"; do
  if [[ ! " ${all[*]} " =~ " $t " ]]; then
    echo "$0: unknown target '$t' (targets: ${all[*]})" >&2
    exit 2
  fi
done

if [[ ! -f $build/build.ninja ]]; then
  CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCSGVOX_FUZZ=ON \
    -DCSGVOX_BUILD_TESTS=OFF -DCSGVOX_BUILD_BENCHMARKS=OFF
fi
cmake --build "$build" --target "${targets[@]/#/fuzz_}"

failed=()
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t
  artifacts=$build/artifacts/$t
  mkdir -p "$corpus" "$artifacts"
  dict=()
  [[ -f $root/fuzz/dict/$t.dict ]] && dict=(-dict="$root/fuzz/dict/$t.dict")
  echo "== fuzz_$t for ${seconds} s"
  if "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$artifacts/" "${dict[@]}" \
      "$corpus" "$root/fuzz/corpus/$t"; then
    echo "== fuzz_$t: clean"
  else
    echo "== fuzz_$t: FAILED (inputs in $artifacts)" >&2
    failed+=("$t")
  fi
done
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "failed: ${failed[*]}" >&2
  exit 1
fi

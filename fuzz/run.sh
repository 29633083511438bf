#!/bin/sh
# Runs each libFuzzer target for SECONDS on a scratch copy of its seed corpus
# (new inputs never land in the repository). Exits non-zero on the first crash,
# leak, timeout or out-of-memory; the crashing input is kept in the scratch
# directory, whose path is printed. Usage: fuzz/run.sh BUILD_DIR SECONDS
set -eu
build=$1
seconds=$2
root=$(cd "$(dirname "$0")" && pwd)
scratch=$(mktemp -d "${TMPDIR:-/tmp}/haze-fuzz-XXXXXX")
for target in scene exr nvdb bsdf; do
  mkdir -p "$scratch/$target" "$scratch/artifacts"
  cp "$root/corpus/$target/"* "$scratch/$target/"
  dict=
  [ -f "$root/$target.dict" ] && dict="-dict=$root/$target.dict"
  echo "fuzz_$target: ${seconds} s, log in $scratch/$target.log"
  # -timeout: one input taking over 10 s is a hang.
  if ! "$build/fuzz_$target" $dict -max_total_time="$seconds" -timeout=10 -print_final_stats=1 \
      -artifact_prefix="$scratch/artifacts/$target-" "$scratch/$target" >"$scratch/$target.log" 2>&1; then
    tail -n 60 "$scratch/$target.log"
    echo "fuzz_$target FAILED: reproduce with $build/fuzz_$target $scratch/artifacts/$target-*" >&2
    exit 1
  fi
  grep -E '^Done|^stat::(number_of_executed_units|average_exec_per_sec|new_units_added)' "$scratch/$target.log"
  grep -E '^#[0-9]+.*(DONE|pulse)' "$scratch/$target.log" | tail -n 1
done
rm -rf "$scratch"

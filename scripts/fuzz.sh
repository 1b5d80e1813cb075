#!/usr/bin/env bash
# Runs every cargo-fuzz target of the repository for SECONDS each, one after the other, and fails if any of
# them finds a crash (panic, abort, timeout, out-of-memory). Installs cargo-fuzz if it is missing; needs no
# nightly toolchain (RUSTC_BOOTSTRAP=1 lets the stable compiler take cargo-fuzz's -Z flags).
#
#   scripts/fuzz.sh SECONDS [TARGET...]      e.g. scripts/fuzz.sh 30, or scripts/fuzz.sh 600 read_ply
#
# Corpora, build output and logs live under target/fuzz/ (FUZZ_DIR to move them), so a second run continues
# from the first run's corpus. A crashing input is saved as target/fuzz/<target>/artifacts/crash-*; turn it
# into a regression test by copying it to <crate>/tests/data/fuzz/<target>/ (see README, "Fuzzing").
set -euo pipefail
cd "$(dirname "$0")/.."

# One line per target: fuzz crate directory, target name, then seed directories (optional). Adding a target
# is adding its line here.
TARGETS=(
  "protocol/fuzz stream_decoder samples protocol/tests/data/fuzz/stream_decoder"
  "protocol/fuzz command_parser protocol/tests/data/fuzz/command_parser"
  "record/fuzz read_recording record/tests/data/fuzz/read_recording"
  "record/fuzz read_strokes record/tests/data/fuzz/read_strokes"
  "recon/fuzz read_obj recon/tests/data recon/tests/data/fuzz/read_obj"
  "recon/fuzz read_off recon/tests/data recon/tests/data/fuzz/read_off"
  "recon/fuzz read_ply recon/tests/data recon/tests/data/fuzz/read_ply"
  "recon/fuzz read_stl recon/tests/data recon/tests/data/fuzz/read_stl"
  "recon/fuzz read_matrix_market recon/tests/data recon/tests/data/fuzz/read_matrix_market"
)

if [[ $# -lt 1 || ! $1 =~ ^[0-9]+$ ]]; then
  echo "usage: $0 SECONDS [TARGET...]" >&2
  exit 2
fi
seconds=$1
shift
only=("$@")

export RUSTC_BOOTSTRAP=1
export PATH="$HOME/.cargo/bin:$PATH"
if ! cargo fuzz --version >/dev/null 2>&1; then
  echo "installing cargo-fuzz" >&2
  cargo install cargo-fuzz --locked
fi

# Debug assertions on (integer overflow panics); no sanitizer by default: the crates deny `unsafe` and a panic is
# what the targets look for. FUZZ_SANITIZER=address also checks the dependencies' unsafe code, at twice the cost.
build_flags=(--release --debug-assertions --sanitizer "${FUZZ_SANITIZER:-none}")
# FUZZ_OPT_LEVEL=1 builds several times faster (faer, under recon, dominates) for short runs such as CI's.
if [[ -n ${FUZZ_OPT_LEVEL:-} ]]; then
  export CARGO_PROFILE_RELEASE_OPT_LEVEL=$FUZZ_OPT_LEVEL CARGO_PROFILE_RELEASE_DEBUG=false
fi
root=$PWD
work=${FUZZ_DIR:-$root/target/fuzz}
mkdir -p "$work"
failed=()
summary=()
for line in "${TARGETS[@]}"; do
  read -r crate target seeds <<<"$line"
  if [[ ${#only[@]} -gt 0 && ! " ${only[*]} " =~ " $target " ]]; then
    continue
  fi
  dir=$work/$target
  mkdir -p "$dir/corpus" "$dir/artifacts"
  seed_dirs=()
  for s in $seeds; do
    [[ -d $s ]] && seed_dirs+=("$root/$s")
  done
  log=$dir/fuzz.log
  echo "=== $target ($crate, ${seconds}s)" >&2
  status=0
  start=$SECONDS
  (
    cd "$crate"
    # The fuzz crates are separate workspaces sharing one build directory, so libFuzzer and the common
    # dependencies are compiled once.
    cargo fuzz build "${build_flags[@]}" --target-dir "$work/build" "$target"
    cargo fuzz run "${build_flags[@]}" --target-dir "$work/build" "$target" \
      "$dir/corpus" "${seed_dirs[@]}" -- \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$dir/artifacts/"
  ) >"$log" 2>&1 || status=$?
  wall=$((SECONDS - start))
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  result=ok
  if [[ $status -ne 0 ]]; then
    result="FAILED (exit $status)"
    failed+=("$target")
    tail -n 40 "$log" >&2
    ls "$dir/artifacts" >&2 || true
  fi
  summary+=("$(printf '%-20s %6ss %12s executions %6ss with build  %s' "$target" "$seconds" "${execs:-?}" "$wall" "$result")")
done

printf '%s\n' "${summary[@]}"
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "fuzzing found crashes in: ${failed[*]} (inputs under $work/<target>/artifacts/)" >&2
  exit 1
fi

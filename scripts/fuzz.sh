#!/usr/bin/env bash
# Builds the libFuzzer targets with clang-14 + ASan + UBSan in BUILD (default build-fuzz) and runs
# each for FUZZ_SECONDS (default 30) from its seed corpus (fuzz/corpus/<target>, copied into
# BUILD/fuzz/corpus/<target> so that new inputs do not land in the repository).
#   scripts/fuzz.sh [BUILD]      FUZZ_SECONDS=600 scripts/fuzz.sh      FUZZ_TARGETS="obj ply" scripts/fuzz.sh
# FUZZ_RUNS=N runs N inputs per target from the fixed seed FUZZ_SEED (default 1) instead of a time
# budget: the same inputs on every machine, which is what CI uses (a red CI is then reproducible).
# Prints one line per target (executions, coverage, features); exits 1 at the first finding, whose
# reproducer libFuzzer leaves in BUILD/fuzz/ (crash-*, timeout-*, leak-*, oom-*).
# The targets honour CORRLAP_MAX_MEMORY as the CLI does: CORRLAP_MAX_MEMORY=256K refuses volumes
# above about 64^3 at the budget check, for long runs of the volume readers (8-30x more executions).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-fuzz}
seconds=${FUZZ_SECONDS:-30}
cxx=${FUZZ_CXX:-clang++-14}
cc=${FUZZ_CC:-clang-14}
if [ ! -f "$build/build.ninja" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER="$cc" \
    -DCMAKE_CXX_COMPILER="$cxx" -DCORRLAP_FUZZ=ON -DCORRLAP_BUILD_TESTS=OFF -DCORRLAP_BUILD_APPS=OFF \
    -DCORRLAP_BUILD_BENCH=OFF >/dev/null
fi
cmake --build "$build" --target fuzzers -j "${JOBS:-$(nproc)}"
read -r -a targets <<<"${FUZZ_TARGETS:-$(cat "$build/fuzz/targets.txt")}"
for t in "${targets[@]}"; do
  # A time-budgeted run grows BUILD/fuzz/corpus/<target> run after run; a FUZZ_RUNS run starts from
  # the checked-in seeds only, so that it sees the same inputs everywhere.
  corpus_dir=corpus
  [ -n "${FUZZ_RUNS:-}" ] && corpus_dir=corpus-seeds && rm -rf "$build/fuzz/$corpus_dir/$t"
  corpus="$build/fuzz/$corpus_dir/$t"
  mkdir -p "$corpus"
  cp -n fuzz/corpus/"$t"/* "$corpus"/ 2>/dev/null || true
  log="$build/fuzz/$t.log"
  # -rss_limit_mb: a reader must refuse absurd sizes before allocating, so 2 GB is plenty.
  budget=(-max_total_time="$seconds")
  [ -n "${FUZZ_RUNS:-}" ] && budget=(-runs="$FUZZ_RUNS" -seed="${FUZZ_SEED:-1}")
  if ! (cd "$build/fuzz" && ./fuzz_"$t" "${budget[@]}" -timeout=10 -rss_limit_mb=2048 \
        -print_final_stats=1 "$corpus_dir/$t" >"$t.log" 2>&1); then
    echo "fuzz_$t: FINDING (see $log)"; tail -40 "$log"; exit 1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  label="${seconds} s"
  [ -n "${FUZZ_RUNS:-}" ] && label="seed ${FUZZ_SEED:-1}"
  printf 'fuzz_%-18s %-8s  executions %10s  coverage %6s edges  features %6s  findings 0\n' "$t" "$label" "$execs" "$cov" "$ft"
done

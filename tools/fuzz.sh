#!/usr/bin/env bash
# Fuzz every file format a user hands organtex (cargo-fuzz, libFuzzer).
#
#   tools/fuzz.sh [SECONDS] [TARGET...]   each target SECONDS (default 600)
#   tools/fuzz.sh --smoke [TARGET...]     each target FUZZ_SMOKE_RUNS inputs
#                                         (default 10000; CI's quick check)
#
# The targets are fuzz/fuzz_targets/*.rs, each calling organtex::fuzz::<name>
# (src/fuzz.rs). On the stable toolchain without a sanitizer (`-s none`);
# FUZZ_ASAN=1 builds with AddressSanitizer instead, which needs
# RUSTC_BOOTSTRAP=1: it is set for that build alone, here, never for the
# normal build. Debug assertions (overflow checks) are on either way.
#
# FUZZ_ARGS adds libFuzzer options (e.g. "-fork=1 -ignore_crashes=1" to go on
# past a crash). fuzz/dicts/<target>.dict, when there, is the target's
# dictionary (keywords: without a sanitizer libFuzzer sees no string
# comparisons).
#
# Seeds are fuzz/corpus/<target>/ (committed); what the fuzzer adds goes to
# fuzz/work/<target>/ (ignored, kept between runs; --smoke adds nothing).
# Every crash, timeout or out-of-memory input is copied to
# tests/data/fuzz-regressions/<target>/, which `cargo test`
# (tests/fuzz_regressions.rs) replays; the script then exits 1. The fuzz
# build skips PNG checksums (the png crate under cfg(fuzzing)): for a PNG
# add a copy with its CRCs recomputed, or the test stops at the checksum.
set -euo pipefail
cd "$(dirname "$0")/.."

smoke=0
seconds=600
if [[ "${1:-}" == "--smoke" ]]; then
    smoke=1
    shift
elif [[ "${1:-}" =~ ^[0-9]+$ ]]; then
    seconds=$1
    shift
elif [[ "${1:-}" == -* ]]; then
    sed -n '2,25p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
runs=${FUZZ_SMOKE_RUNS:-10000}

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "fuzz.sh: installing cargo-fuzz"
    cargo install cargo-fuzz --locked
fi

build=(+stable fuzz build --release --debug-assertions)
if [[ "${FUZZ_ASAN:-0}" == 1 ]]; then
    build+=(-s address --target-dir fuzz/target/asan)
    bin=fuzz/target/asan
    bootstrap=(env RUSTC_BOOTSTRAP=1)
else
    build+=(-s none)
    bin=fuzz/target
    bootstrap=()
fi
bin=$bin/$(rustc +stable -vV | sed -n 's/^host: //p')/release

targets=("$@")
if [[ ${#targets[@]} -eq 0 ]]; then
    mapfile -t targets < <(cargo fuzz list)
fi

start=$(date +%s)
"${bootstrap[@]}" cargo "${build[@]}"
echo "fuzz.sh: built in $(( $(date +%s) - start )) s"

mkdir -p fuzz/logs
failed=()
summary=()
start=$(date +%s)
for t in "${targets[@]}"; do
    log=fuzz/logs/$t.log
    artifacts=fuzz/artifacts/$t
    rm -rf "$artifacts"
    mkdir -p "$artifacts"
    if [[ $smoke == 1 ]]; then
        work=$(mktemp -d)
        limit=(-runs="$runs" -seed=1)
    else
        work=fuzz/work/$t
        mkdir -p "$work"
        limit=(-max_total_time="$seconds")
    fi
    # The targets' scratch files (src/fuzz.rs), removed after the run.
    scratch=$(mktemp -d)
    dict=()
    [[ -f fuzz/dicts/$t.dict ]] && dict=(-dict="fuzz/dicts/$t.dict")
    # Inputs the fuzzer adds go to the first folder; the seeds are read only.
    status=0
    TMPDIR=$scratch "$bin/$t" "${limit[@]}" "${dict[@]}" -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$artifacts/" ${FUZZ_ARGS:-} "$work" "fuzz/corpus/$t" >"$log" 2>&1 ||
        status=$?
    rm -rf "$scratch"
    [[ $smoke == 1 ]] && rm -rf "$work"

    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    # Fork mode prints no final stats, only "#N: cov: ..." lines.
    [[ -n $execs ]] || execs=$(grep -o '^#[0-9]*:' "$log" | tail -1 | tr -d '#:')
    cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
    ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
    result=ok
    found=()
    for a in "$artifacts"/crash-* "$artifacts"/timeout-* "$artifacts"/oom-* "$artifacts"/leak-*; do
        [[ -f $a ]] && found+=("$a")
    done
    if [[ ${#found[@]} -gt 0 ]]; then
        mkdir -p "tests/data/fuzz-regressions/$t"
        cp "${found[@]}" "tests/data/fuzz-regressions/$t/"
        result="FOUND ${#found[@]}: $(basename -a "${found[@]}" | tr '\n' ' ')(see $log)"
        failed+=("$t")
    elif [[ $status != 0 ]]; then
        result="FAILED (exit $status, see $log)"
        failed+=("$t")
    fi
    summary+=("$(printf '%-9s execs %-10s cov %-6s ft %-6s %s' "$t" "${execs:-?}" "${cov:-?}" "${ft:-?}" "$result")")
    echo "${summary[-1]}"
done

echo
echo "fuzz.sh: $(if [[ $smoke == 1 ]]; then echo "smoke, $runs runs"; else echo "$seconds s"; fi) a target," \
    "$(( $(date +%s) - start )) s in all$([[ ${FUZZ_ASAN:-0} == 1 ]] && echo ", AddressSanitizer")"
printf '%s\n' "${summary[@]}"
if [[ ${#failed[@]} -gt 0 ]]; then
    echo "fuzz.sh: inputs that fail are in tests/data/fuzz-regressions/ (replayed by cargo test): ${failed[*]}"
    exit 1
fi

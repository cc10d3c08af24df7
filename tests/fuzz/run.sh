#!/bin/bash
# Runs each libFuzzer harness of a -DANVIL_FUZZ=ON build for SECONDS (default 15) from its seeds
# (tests/fuzz/corpus/NAME, and the shipped configs and displays for the config harnesses).
# Fails when a harness finds a crash, a leak, undefined behaviour, a timeout (10 s for one
# input) or an allocation over 2 GB; the input that did it is left in WORK (default a
# temporary folder, kept then) for `fuzz_NAME INPUT` to replay.
#   tests/fuzz/run.sh BUILD_DIR [SECONDS] [NAME...]
set -u
build=$(cd "$1" && pwd)
seconds=${2:-15}
shift $(($# < 2 ? $# : 2))
src=$(cd "$(dirname "$0")/../.." && pwd)
work=${ANVIL_FUZZ_WORK:-$(mktemp -d)}
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(config display_config script transfer wrf extfile coast dtrack vrpn cm1 cf)
failed=0
for name in "${names[@]}"; do
    seeds=("$src/tests/fuzz/corpus/$name")
    case $name in
    config) seeds+=("$src/configs") ;;
    display_config) seeds+=("$src/displays") ;;
    esac
    mkdir -p "$work/$name/corpus" "$work/$name/crashes"
    (cd "$work/$name" && UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
        LSAN_OPTIONS="suppressions=$src/tests/lsan.supp:print_suppressions=0" \
        "$build/tests/fuzz/fuzz_$name" -max_total_time="$seconds" -timeout=10 \
        -rss_limit_mb=2048 -malloc_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$work/$name/crashes/" "$work/$name/corpus" "${seeds[@]}" \
        >"$work/$name/log" 2>&1)
    rc=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/$name/log")
    if [ $rc -ne 0 ]; then
        echo "fuzz_$name: FAILED (exit $rc) after ${runs:-?} runs; input and log in $work/$name:"
        grep -E "ERROR|SUMMARY|runtime error|Test unit written" "$work/$name/log" | head -8
        failed=1
    else
        echo "fuzz_$name: ${runs:-?} runs in ${seconds} s, no failure"
    fi
done
[ $failed -eq 0 ] && [ -z "${ANVIL_FUZZ_WORK:-}" ] && rm -rf "$work"
exit $failed

#!/bin/bash
# Builds the tracker parsers' libFuzzer harnesses with clang (AddressSanitizer, UBSan) and runs
# each for SECONDS (default 15) from its seed corpus; fails on a crash, a leak or a broken
# invariant.  Usage: tests/fuzz/run.sh [SECONDS] [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-15}
out=${2:-build-fuzz}
mkdir -p "$out"
flags="-g -O1 -std=c11 -D_DEFAULT_SOURCE -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -Isrc"
for name in dtrack vrpn; do
    clang $flags "tests/fuzz/fuzz_$name.c" "src/input/$name.c" -lm -o "$out/fuzz_$name"
    corpus="$out/corpus-$name"
    mkdir -p "$corpus"
    cp tests/fuzz/seeds/$name/* "$corpus/"
    echo "fuzz_$name: $seconds s"
    "$out/fuzz_$name" -max_total_time="$seconds" -timeout=5 -rss_limit_mb=1024 \
        -print_final_stats=1 "$corpus" 2>"$out/fuzz_$name.log" ||
        { tail -40 "$out/fuzz_$name.log"; exit 1; }
    grep -E "stat::number_of_executed_units|Done" "$out/fuzz_$name.log" | tail -2
done

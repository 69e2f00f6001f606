#!/bin/sh
# One fuzz target: every input in its regression folder first, then MVOD_FUZZ_SECONDS (default
# 3) of fuzzing from them. New inputs go to a folder in the build directory, never the source
# tree; a crashing input is written to crash-* here, to keep under tests/fuzz/NAME/ once fixed.
# libFuzzer fails with 77 by default, which meson would read as "skipped": 1 instead.
set -eu
exe=$1
regress=$2
name=$(basename "$regress")
corpus=corpus/$name
mkdir -p "$corpus"
exec "$exe" -max_total_time="${MVOD_FUZZ_SECONDS:-3}" -timeout=10 -rss_limit_mb=4096 \
	-error_exitcode=1 -timeout_exitcode=1 \
	-print_final_stats=1 -artifact_prefix="$name-" "$corpus" "$regress"

#!/bin/sh
# One fuzz target: every input in its regression folder first, then fuzzing from them.
# With MVOD_FUZZ_SECONDS set (make fuzz), a time-bounded run from a random seed explores; without
# it (make test), a fixed seed and a fixed number of runs make the test repeatable: what passes
# here passes in CI, and a failure reproduces with the same command. New inputs go to a folder
# in the build directory, never the source tree; a crashing input is written to NAME-crash-* here,
# to keep under fuzz/corpus/NAME/ once fixed.
# libFuzzer fails with 77 by default, which meson would read as "skipped": 1 instead.
set -eu
exe=$1
regress=$2
runs=${3:-50000} # the fixed-seed stage's runs (fuzz/meson.build)
name=$(basename "$regress")
corpus=corpus/$name
if [ -n "${MVOD_FUZZ_SECONDS:-}" ]; then
	budget="-max_total_time=$MVOD_FUZZ_SECONDS"
else
	rm -rf "$corpus" # what an earlier run found would change what this one does
	budget="-seed=1 -runs=${MVOD_FUZZ_RUNS:-$runs}"
fi
mkdir -p "$corpus"
# shellcheck disable=SC2086 # $budget is one or two options
exec "$exe" $budget -timeout=10 -rss_limit_mb=4096 \
	-error_exitcode=1 -timeout_exitcode=1 \
	-print_final_stats=1 -artifact_prefix="$name-" "$corpus" "$regress"

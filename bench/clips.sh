#!/usr/bin/env bash
# The clip table: one `mvod bench` row for each front end, mode, scale and KITTI clip in
# ../shared/data (2 x 2 x 3 x 2 = 24 rows by default, about a minute), as BENCHMARKS.md compares
# accuracy across changes. --scale height uses KITTI's camera height, 1.65 m.
#
# Usage: [FE="klt orb"] [MODES="map twoview"] [SCALES="gt auto height"] [CLIPS="06 07"] \
#            [JOBS=2] bench/clips.sh [BUILDDIR] [-- BENCH_ARGS...]
#   e.g. FE=klt MODES=map bench/clips.sh build -- --tracks 1000
# BENCH_ARGS go to every row. Writes into OUT (default BUILDDIR/bench-out/clips), for each
# run FE-MODE-SCALE-CLIP: .row (mvod bench's output) and .traj (its trajectory); and
# table.md, the rows under one header with the run's name first, which it also prints.
# JOBS rows run at once: the accuracy columns do not depend on it, the timing columns do.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
bench_args "$@"
out=${OUT:-$build/bench-out/clips}
mkdir -p "$out"
runs=()
for c in ${CLIPS:-06 07}; do
	need "$data/kitti-odometry-$c-clip/sequences/$c"
done
for fe in ${FE:-klt orb}; do
	for mode in ${MODES:-map twoview}; do
		for scale in ${SCALES:-gt auto height}; do
			for c in ${CLIPS:-06 07}; do
				height=()
				[ "$scale" = height ] && height=(--camera-height 1.65)
				run=$fe-$mode-$scale-$c
				runs+=("$run")
				spawn bench_row "$out/$run.row" \
					--source "kitti:$data/kitti-odometry-$c-clip/sequences/$c" \
					--frontend "$fe" --mode "$mode" --scale "$scale" "${height[@]}" \
					--trajectory "$out/$run.traj" --log-level warn "${extra[@]}"
			done
		done
	done
done
wait
{
	grep -m1 '^| detector' "$out/${runs[0]}.row" | sed 's/^/| run /'
	grep -m1 '^|---' "$out/${runs[0]}.row" | sed 's/^/|---/'
	for run in "${runs[@]}"; do
		echo "| $run $(grep '^| [a-z]' "$out/$run.row" | grep -v '^| detector' | tail -1)"
	done
} >"$out/table.md"
cat "$out/table.md"

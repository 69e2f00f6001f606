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
# DRAWS="480 500 520": every row once for each of these --tracks counts (named ...-tN), then a
# second table, means.md, of each row's mean over them: which tracks live moves the free-scale
# and height rows by chance far more than most changes do, so BENCHMARKS.md judges a change by
# the mean over draws (3 times the rows and the minutes).
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
				for t in ${DRAWS:--}; do
					height=() tracks=() run=$fe-$mode-$scale-$c
					[ "$scale" = height ] && height=(--camera-height 1.65)
					[ "$t" != - ] && tracks=(--tracks "$t") && run=$run-t$t
					runs+=("$run")
					spawn bench_row "$out/$run.row" \
						--source "kitti:$data/kitti-odometry-$c-clip/sequences/$c" \
						--frontend "$fe" --mode "$mode" --scale "$scale" \
						"${height[@]}" "${tracks[@]}" --trajectory "$out/$run.traj" \
						--log-level warn "${extra[@]}"
				done
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
[ -z "${DRAWS:-}" ] && exit 0
{
	echo
	echo "Means over --tracks ${DRAWS// //}:"
	echo
	runs_table "err_avg|RPE dir deg|ATE m|scale drift" err_avg rpe_dir_deg ate_m scale_drift |
		draw_means
} >"$out/means.md"
cat "$out/means.md"

#!/usr/bin/env bash
# The KITTI clip table: one `mvod bench` row for each front end, mode, scale and KITTI clip in
# ../shared/data (2 x 2 x 3 x 2 = 24 rows by default, about two minutes), its accuracy columns
# (deterministic: the same binary gives the same digits), as BENCHMARKS.md's "kitti" and
# "metric" tables. --scale height uses KITTI's camera height, 1.65 m; the external scales
# (bench/lib.sh's scale_args) the clip's ground-truth speed.
#
# Usage: [FE="klt orb"] [MODES="map twoview"] [SCALES="gt auto height"] [CLIPS="06 07"] \
#            [JOBS=2] bench/clips.sh [BUILDDIR] [-- BENCH_ARGS...]
#   e.g. FE=klt MODES=map bench/clips.sh build -- --tracks 1000
# SCALES may also name external, external-noise, external-bias. BENCH_ARGS go to every row.
# Writes into OUT (default BUILDDIR/bench-out/clips), for each run FE-MODE-SCALE-CLIP: .row
# (mvod bench's whole output, timings too) and .traj (its trajectory); and table.md, the runs'
# accuracy columns under one header, which it also prints. JOBS rows run at once.
# DRAWS="480 500 520": every row once for each of these --tracks counts (named ...-tN), then a
# second table, means.md, of each row's mean over them: which tracks live moves the free-scale
# and height rows by chance far more than most changes do, so a change is judged by the mean
# over draws (3 times the rows and the minutes).
set -euo pipefail
. "$(dirname "$0")/lib.sh"
bench_args "$@"
out=${OUT:-$build/bench-out/clips}
mkdir -p "$out"
runs=() cam_height=1.65
for c in ${CLIPS:-06 07}; do
	need "$data/kitti-odometry-$c-clip/sequences/$c"
done
for fe in ${FE:-klt orb}; do
	for mode in ${MODES:-map twoview}; do
		for scale in ${SCALES:-gt auto height}; do
			for c in ${CLIPS:-06 07}; do
				clip=$data/kitti-odometry-$c-clip
				gt=$clip/poses/$c.txt times=$clip/sequences/$c/times.txt
				run_bench "$fe-$mode-$scale-$c" "$scale" --source "kitti:$clip/sequences/$c" \
					--frontend "$fe" --mode "$mode"
			done
		done
	done
done
wait
runs_table "$acc_titles" "${acc_cols[@]}" | tee "$out/table.md"
[ -z "${DRAWS:-}" ] && exit 0
{
	echo
	echo "Means over --tracks ${DRAWS// //}:"
	echo
	draw_means <"$out/table.md"
} | tee "$out/means.md"

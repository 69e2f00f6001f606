#!/usr/bin/env bash
# Long drives: `mvod bench` (map mode) along mvod-synth renders of the whole KITTI 06, 07 and 00
# ground truth in ../shared/data (640x192, KITTI's field of view; 1101, 1101 and 4541 frames), in
# free scale (auto) and from the camera's height (1.6 m, the synthetic ground's; SCALES as
# bench/clips.sh's, e.g. external), as BENCHMARKS.md judges accuracy on drives 5-70 times the
# clips' length (BENCHMARKS.md's "long" table). Prints KITTI's t_rel % per run and their mean:
# which corners become tracks moves a drive's free-scale t_rel by points (the track cap alone
# does), so judge a change by the mean over drives and draws (DRAWS below).
#
# Usage: [DRIVES="06 07 00"] [SCALES="auto height"] [DRAWS="480 500 520"] [JOBS=2] [FULL=1] \
#            bench/long.sh [BUILDDIR] [-- BENCH_ARGS...]
# BENCH_ARGS go to every run. DRAWS: each run once for each of these --tracks counts (named
# ...-tN), and a second table of each drive and scale's means over them, 3 times the minutes.
# Renders missing from the cache (see bench/lib.sh) are made first: on 2 shared cores about 3
# minutes each for 06 and 07, 10 for 00 (360 MB); then about 5 minutes of runs (auto, height
# and external). FULL=1: the drives at KITTI's own size,
# 1240x376 (fx 707), where klt.c's rules for frames 1024 px wide or more apply: a minute each
# for 06 and 07, 4 for 00 (1.5 GB); then 8 minutes of runs. Writes into OUT (default
# BUILDDIR/bench-out/long, with FULL=1 long-full), for each run kNN-SCALE[-tN]: .row (mvod
# bench's output) and .traj (its trajectory); and table.md, which it also prints.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
bench_args "$@"
full=
[ "${FULL:-0}" = 1 ] && full=-full
out=${OUT:-$build/bench-out/long$full}
mkdir -p "$out"
declare -A dir
for d in ${DRIVES:-06 07 00}; do
	dir[$d]=$(drive "$d")
done
runs=() cam_height=1.6 times=
for d in ${DRIVES:-06 07 00}; do
	gt=${dir[$d]}/gt.tum
	for scale in ${SCALES:-auto height}; do
		run_bench "k$d-$scale" "$scale" --source "file:${dir[$d]}/video.mkv" \
			--calib "${dir[$d]}/calib.json" --gt "$gt"
	done
done
wait
runs_table "frames|t_rel %|r_rel deg/100m|ATE m|scale drift" \
	frames t_rel_pct r_rel_deg_100m ate_m scale_drift >"$out/table.md"
means=
[ -n "${DRAWS:-}" ] && means=$(draw_means <"$out/table.md")
awk -F' *[|] *' 'NR > 2 && $4 != "-" { s += $4; n++ }
	END { if (n) printf "mean t_rel %%: %.2f over %d runs\n", s / n, n }' "$out/table.md" >>"$out/table.md"
[ -n "$means" ] && printf '\nMeans over --tracks %s:\n\n%s\n' "${DRAWS// //}" "$means" >>"$out/table.md"
cat "$out/table.md"

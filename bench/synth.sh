#!/usr/bin/env bash
# mvod-synth renderings (exact ground truth): one `mvod bench` row for each case and scale, at
# mvod's defaults (map mode, KLT), as BENCHMARKS.md's "synth", "metric" and "datasets" tables.
# Renders are cached (bench/lib.sh's render). Cases (640x480, 10 Hz, the street's ground 1.6 m
# below the camera: the height scale's --camera-height):
#   forward       100 frames straight at 1 m/s (0.1 m a frame)
#   turn          the demo's: 150 frames at 3 m/s with a 90 deg left turn
#   circle        120 frames of a 6 m circle
#   figure8       300 frames: a left circle, then a right one
#   stop-go       100 frames of a gentle curve, braking to a stop and pulling away
#   rotate        rotate-in-place, 60 frames (no translation: ATE and path "-")
#   noisy         forward with 2 grey levels of noise and a 1 px blur
#   radtan fisheye fov   the turn, 80 frames at 1 m/s, through a radial-tangential lens
#                 (k1 -0.3, k2 0.1), a Kannala-Brandt fisheye (f 300 px) and DSO's FOV lens (0.9)
#   street        forward at 2 m/s, 60 frames (the metric_scale test's street)
#   mkv png euroc tum tum-mono kitti-raw   the turn, 80 frames, no lens, written in each
#                 layout and read through its own reader (docs/datasets.md): every row the same
#
# Usage: [CASES="forward turn ..."] [SCALES="gt auto"] [JOBS=2] bench/synth.sh [BUILDDIR] \
#            [-- BENCH_ARGS...]
# SCALES as bench/clips.sh's. Writes into OUT (default BUILDDIR/bench-out/synth) CASE-SCALE.row
# and .traj, and table.md, which it also prints. About 2 minutes the first time (renders), 30 s
# after.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
bench_args "$@"
out=${OUT:-$build/bench-out/synth}
mkdir -p "$out"
runs=() cam_height=1.6 times=

# render_case CASE: sets dir (the render, made when missing) and src (mvod's source arguments).
render_case() {
	local turn=(--path turn --frames 80) r
	case $1 in
	forward) r=(--frames 100) ;;
	turn) r=(--path turn --frames 150 --speed 3) ;;
	circle) r=(--path circle --frames 120) ;;
	figure8) r=(--path figure8 --frames 300) ;;
	stop-go) r=(--path stop-go --frames 100) ;;
	rotate) r=(--path rotate-in-place --frames 60) ;;
	noisy) r=(--frames 100 --noise 2 --blur 1) ;;
	radtan) r=("${turn[@]}" --distortion=-0.3,0.1,0,0) ;;
	fisheye) r=("${turn[@]}" --fisheye 0.05,0.01,0,0 --fx 300) ;;
	fov) r=("${turn[@]}" --fov 0.9) ;;
	street) r=(--frames 60 --speed 2) ;;
	mkv) r=("${turn[@]}") ;;
	png | euroc | tum | tum-mono | kitti-raw) r=("${turn[@]}" --format "$1") ;;
	*) echo "synth.sh: no case $1" >&2 && exit 2 ;;
	esac
	case $1 in png | euroc | tum | tum-mono | kitti-raw) ;; *) r+=(--codec raw) ;; esac
	dir=$(render "synth-$1" "${r[@]}")
	gt=$dir/gt.tum
	case $1 in
	png) src=(--source "images:$dir/images" --calib "$dir/calib.json" --gt "$gt") ;;
	euroc) src=(--source "euroc:$dir") ;;
	tum) src=(--source "tum:$dir" --calib "$dir/calib.json") ;;
	tum-mono) src=(--source "tum:$dir" --gt "$dir/gt.kitti") ;; # its gt.tum is on another clock
	kitti-raw) src=(--source "kitti-raw:$dir/2011_09_26/2011_09_26_drive_0001_sync") ;;
	*) src=(--source "file:$dir/video.mkv" --calib "$dir/calib.json" --gt "$gt") ;;
	esac
}

for c in ${CASES:-forward turn circle figure8 stop-go rotate noisy radtan fisheye fov}; do
	render_case "$c"
	for scale in ${SCALES:-gt auto}; do
		run_bench "$c-$scale" "$scale" "${src[@]}"
	done
done
wait
runs_table "$acc_titles" "${acc_cols[@]}" | tee "$out/table.md"

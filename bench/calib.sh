#!/usr/bin/env bash
# Calibration: `mvod calibrate` on mvod-synth's board views, whose intrinsics are exact (640x480,
# fx 500, fy 505, cx 325, cy 235, a radial-tangential lens k1 -0.25 k2 0.08 p1 0.001 p2
# -0.0005, or a Kannala-Brandt fisheye, 1 grey level of noise, 60 views), and on OpenCV's real
# photos in ../shared/data (13 chessboard views, 4 ChArUco views) against OpenCV's own
# calibration of them. Prints a table: views used, fx, fy, cx, cy as "estimate (truth)" and the
# RMS reprojection error. Deterministic: the same binary gives the same digits.
#
# Usage: [CASES="charuco chessboard fisheye photos-chessboard photos-charuco"] \
#            bench/calib.sh [BUILDDIR]
# Writes CASE.json (the calibration) and CASE.log into OUT (default BUILDDIR/bench-out/calib);
# renders are cached (bench/lib.sh's render). Exits 77 (skipped) at a photos case when
# ../shared/data is absent. About a minute (ChArUco detection ~30 ms a view, a chessboard's
# 100-150 ms).
set -euo pipefail
. "$(dirname "$0")/lib.sh"
bench_args "$@"
out=${OUT:-$build/bench-out/calib}
mkdir -p "$out"
charuco=charuco:5x7:0.04:0.02:DICT_6X6_250 chess=chessboard:9x6:0.025
lens=(--views 60 --format png --noise 1 --fx 500 --fy 505 --cx 325 --cy 235)
radtan=--distortion=-0.25,0.08,0.001,-0.0005

# row NAME BOARD TRUTH SOURCE [CALIBRATE_ARGS...]: calibrates SOURCE and prints NAME's row
# against TRUTH (mvod JSON, or an OpenCV YAML's camera_matrix).
row() {
	local name=$1 board=$2 truth=$3 src=$4
	shift 4
	"$mvod" calibrate --source "$src" --board "$board" --out "$out/$name.json" "$@" \
		>"$out/$name.log" 2>&1 || { echo "calib.sh: $name failed: see $out/$name.log" >&2 && return 1; }
	python3 - "$name" "$out/$name.json" "$truth" <<'PY'
import json, re, sys
name, est, truth = sys.argv[1:]
e = json.load(open(est))
k = e['K']
if truth.endswith('.json'):
	t = json.load(open(truth))['K']
	t, trms = (t[0][0], t[1][1], t[0][2], t[1][2]), None
else:
	y = open(truth).read()
	m = [float(v) for v in re.search(r'camera_matrix:.*?data: *\[([^]]*)\]', y, re.S).group(1).split(',')]
	t, trms = (m[0], m[4], m[2], m[5]), float(re.search(r'avg_reprojection_error: *(\S+)', y).group(1))
cells = ['%.2f (%.6g)' % (a, b) for a, b in zip((k[0][0], k[1][1], k[0][2], k[1][2]), t)]
rms = '%.3f' % e['rms_px'] + (' (%.3f)' % trms if trms is not None else '')
print('| %s | %d | %s | %s |' % (name, len(e['views_used']) if isinstance(e['views_used'], list)
	else e['views_used'], ' | '.join(cells), rms))
PY
}

echo "| run | views | fx | fy | cx | cy | RMS px |"
echo "|---|--:|--:|--:|--:|--:|--:|"
for c in ${CASES:-charuco chessboard fisheye photos-chessboard photos-charuco}; do
	case $c in
	charuco | chessboard)
		board=$charuco
		[ $c = chessboard ] && board=$chess
		d=$(render "calib-$c" --board "$board" "${lens[@]}" "$radtan")
		row "$c" "$board" "$d/calib.json" "images:$d/images" ;;
	fisheye)
		d=$(render calib-fisheye --board "$charuco" "${lens[@]}" --fisheye 0.05,0.01,-0.005,0.001)
		row "$c" "$charuco" "$d/calib.json" "images:$d/images" --model fisheye ;;
	photos-*)
		need "$data/opencv-chessboard" "$data/opencv-charuco"
		if [ $c = photos-charuco ]; then
			row "$c" "$charuco" "$data/opencv-charuco/params/tutorial_camera_charuco.yml" \
				"images:$data/opencv-charuco/calibration_images"
			continue
		fi
		# The set mixes the left and right cameras: the left ones only.
		mkdir -p "$out/left"
		ln -sf "$data"/opencv-chessboard/images/left*.jpg "$out/left/"
		row "$c" "$chess" "$data/opencv-chessboard/params/left_intrinsics.yml" "images:$out/left" ;;
	*) echo "calib.sh: no case $c" >&2 && exit 2 ;;
	esac
done

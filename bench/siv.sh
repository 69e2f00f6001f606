#!/usr/bin/env bash
# The reference implementation for bench/fps.sh (MVOD_REF_CMD): SIV_project at d2ab945
# (github.com/lorenzoorsingher/SIV_project: Python, OpenCV 4.9 and numpy as its requirements.txt
# pins them), set up outside this repository (nothing here installs or contains it), run on a
# KITTI clip as the reference runs: ORB, 1000 features, brute force sorted, ground-truth step
# lengths (`vo.py -m kitti -nd -fm 0 -nf 1000`). Prints its err_avg (../shared/eval.py on its
# poses: the formula mvod bench uses) and, last, its frames a second (its own count: the frame
# loop, without start-up).
#
# Usage: SIV=DIR [SIV_PYTHON=PYTHON] bench/siv.sh NN CLIPDIR
#   NN: 06 or 07; CLIPDIR: ../shared/data/kitti-odometry-NN-clip (sequences/NN, poses/NN.txt);
#   SIV_PYTHON: a Python with the reference's requirements (default DIR/venv/bin/python).
#   e.g. SIV=~/SIV_project bench/run.sh speed
set -euo pipefail
nn=$1 clip=$(cd "$2" && pwd -P)
siv=${SIV:?set SIV to a checkout of SIV_project d2ab945}
py=${SIV_PYTHON:-$siv/venv/bin/python}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# vo.py reads DIR/dataset/sequences/NN and DIR/dataset/poses/NN.txt.
mkdir -p "$work/dataset" "$work/out"
ln -s "$clip/sequences" "$clip/poses" "$work/dataset/"
(cd "$siv" && "$py" vo.py -m kitti -s "$((10#$nn))" -nd -fm 0 -nf 1000 -ki "$work" -kp "$work" \
	-o "$work/out" >"$work/log" 2>&1) || { tail "$work/log" >&2 && exit 1; }
"$py" - "$work/out" <<'PY'
import json, sys
d = sys.argv[1]
with open(d + '/est.kitti', 'w') as f:
	for p in json.load(open(d + '/est.json')):
		f.write(' '.join('%.9g' % v for v in p) + '\n')
PY
"$py" "${MVOD_EVAL:-$(dirname "$0")/../../shared/eval.py}" "$work/out/est.kitti" "$clip/poses/$nn.txt" \
	--est-format kitti --gt-format kitti | sed -n 's/.*\(err_avg=[0-9.]*\).*/\1/p'
"$py" -c 'import json, sys; print("%.1f" % json.load(open(sys.argv[1]))["steps_sec"])' \
	"$work/out/settings.json"

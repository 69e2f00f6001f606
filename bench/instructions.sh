#!/usr/bin/env bash
# Instructions a frame under callgrind: deterministic where wall time is not, so this is how
# BENCHMARKS.md compares speed across changes. Every thread counts (decoding included). Two
# runs, N1 and N2 frames, give (total(N2) - total(N1)) / (N2 - N1): start-up and the first
# frames' set-up cancel out.
#   default  the KITTI 06 clip in ../shared/data, frames 3-20 (N1 = 2, N2 = 20); mvod's default
#            mode (map, --scale auto)
#   --clip NN  the KITTI NN clip instead (06 or 07)
#   --whole    frames 3 to the clip's last (N2 = its frames: 51 on 06, 160 on 07), the average
#              over the clip that issue 13 counts; frames 3-20 are map mode's start, where
#              keyframes and bundle adjustment come more often
#   --s640   a 640x480 mvod-synth street (`mvod-synth --size 640x480 --frames 300 --codec raw`,
#            uncompressed: nothing to decode), frames 51-300; rendered into the cache when missing
#
# Usage: bench/instructions.sh [--s640 | --clip NN] [--whole] [--funcs|--incl] [--top N] [BUILDDIR]
#            [-- MVOD_ARGS...]
#   e.g. bench/instructions.sh /work/main/build -- --scale gt
#   --funcs  also list the instructions a frame of the top N functions (self cost), largest first
#   --incl   the same, inclusive (a function with everything it calls)
#   --top N  how many functions (default 30)
# MVOD_ARGS go to every mvod run (`--mode twoview`, `--tracks 1000`, ...). The environment
# passes through (OPENCV_FOR_THREADS_NUM=1 puts OpenCV's work on the main thread).
# Callgrind files land in OUT (default BUILDDIR/bench-out/instructions), named TAG.N (TAG
# default kitti06 or s640; set TAG to keep several). Takes about 15 s (--s640: 45 s, and 15 s to render).
# Needs valgrind (callgrind) and Python 3.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
s640=0 funcs= top=30 builddir= nn=06 whole=0
while [ $# -gt 0 ]; do
	case $1 in
	--s640) s640=1 ;;
	--clip) nn=$2 && shift ;;
	--whole) whole=1 ;;
	--funcs) funcs=self ;;
	--incl) funcs=incl ;;
	--top) top=$2 && shift ;;
	-h | --help) usage ;;
	--) shift && break ;;
	-*) usage 2 >&2 ;;
	*) builddir=$1 ;;
	esac
	shift
done
bench_init "$builddir"
command -v valgrind >/dev/null || { echo "valgrind absent: skipped" >&2 && exit 77; }

if [ $s640 = 1 ]; then
	dir=$(render s640 --size 640x480 --frames 300 --codec raw)
	src=(--source "file:$dir/video.mkv" --calib "$dir/calib.json")
	n1=50 n2=300 tag=${TAG:-s640} what="640x480 mvod-synth street"
else
	clip=$data/kitti-odometry-$nn-clip/sequences/$nn
	need "$clip"
	src=(--source "kitti:$clip")
	n1=2 n2=20 tag=${TAG:-kitti$nn} what="KITTI $nn clip"
	[ $whole = 1 ] && n2=$(find "$clip/image_0" -name '*.png' | wc -l)
fi
out=${OUT:-$build/bench-out/instructions}
mkdir -p "$out"

total() { sed -n 's/^totals: *//p' "$1"; }
for n in $n1 $n2; do
	f=$out/$tag.$n
	valgrind --tool=callgrind --callgrind-out-file="$f" "$mvod" "${src[@]}" --no-lcm \
		--max-frames $n "$@" >/dev/null 2>"$f.err" || { tail "$f.err" >&2 && exit 1; }
done
frames=$((n2 - n1))
awk -v a="$(total "$out/$tag.$n2")" -v b="$(total "$out/$tag.$n1")" -v n=$frames \
	-v what="$what, frames $((n1 + 1))-$n2${*:+, $*}" \
	'BEGIN { printf "%.2fe6 instructions a frame (%s)\n", (a - b) / n / 1e6, what }'
[ -z "$funcs" ] && exit 0

# The same difference per function, from callgrind_annotate's listing of each file.
echo "e6 instructions a frame by function ($funcs), frames $((n1 + 1))-$n2:"
python3 - "$out/$tag.$n2" "$out/$tag.$n1" $frames $funcs "$top" <<'EOF'
import re, subprocess, sys
long, short, frames, how, top = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], int(sys.argv[5])
def cost(path):
	cmd = ['callgrind_annotate', '--threshold=100'] + (['--inclusive=yes'] if how == 'incl' else [])
	listing = subprocess.run(cmd + [path], capture_output=True, text=True, check=True).stdout
	d = {}
	for line in listing.splitlines():
		m = re.match(r'\s*([\d,]+) \([^)]*\)\s+(\S.*:.*)', line)
		if m:
			d[m.group(2)] = d.get(m.group(2), 0) + int(m.group(1).replace(',', ''))
	return d
a, b = cost(long), cost(short)
rows = sorted(((a.get(k, 0) - b.get(k, 0)) / frames / 1e6, k) for k in set(a) | set(b))
for v, k in reversed(rows[-top:]):
	print('%8.2f  %s' % (v, k[:150]))
EOF

#!/usr/bin/env bash
# Reproduces the numbers in BENCHMARKS.md: the KITTI clips in ../shared/data (when present) and
# a synthetic sequence, each run end to end by the real binary. Timing lives here, never in tests.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
data=${MVOD_DATA:-$root/../shared/data}
out=$(mktemp -d /tmp/mvod-bench-XXXXXX)
trap 'rm -rf "$out"' EXIT
export LCM_DEFAULT_URL=memq://

echo "# mvod bench, $(date -u +%Y-%m-%d)"
echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; mvod $("$build/mvod" --version)"
echo

run() {
	local name=$1
	shift
	echo "## $name"
	echo "\$ mvod $*"
	"$build/mvod" --no-lcm "$@" 2>/dev/null | sed 's/^mvod: /    /'
	echo
}

for seq in 06 07; do
	dir=$data/kitti-odometry-$seq-clip
	if [ -d "$dir" ]; then
		run "KITTI $seq clip, ground-truth scale" --source "kitti:$dir/sequences/$seq" \
			--gt "$dir/poses/$seq.txt" --scale gt
	else
		echo "## KITTI $seq clip: $dir absent, skipped"
	fi
done

"$build/tools/mvod-synth" --path figure8 --frames 300 --out "$out/fig8" >/dev/null
run "mvod-synth figure8, 300 frames 640x480, free scale" --source "file:$out/fig8/video.mkv" \
	--calib "$out/fig8/calib.json" --gt "$out/fig8/gt.tum"
run "mvod-synth figure8, 300 frames 640x480, ground-truth scale" \
	--source "file:$out/fig8/video.mkv" --calib "$out/fig8/calib.json" --gt "$out/fig8/gt.tum" \
	--scale gt

# Instruction counts repeat exactly where wall time does not: compare these across changes.
dir=$data/kitti-odometry-06-clip
if command -v valgrind >/dev/null && [ -d "$dir" ]; then
	echo "## callgrind, KITTI 06 clip, first 20 frames, ground-truth scale"
	valgrind --tool=callgrind --callgrind-out-file="$out/cg.out" "$build/mvod" --no-lcm -q \
		--source "kitti:$dir/sequences/06" --gt "$dir/poses/06.txt" --scale gt --max-frames 20 \
		2>&1 | sed -n 's/.*Collected : /    instructions: /p'
	callgrind_annotate "$out/cg.out" 2>/dev/null | grep -E '^ *[0-9,]+ \(' | sed -n '2,6p'
fi

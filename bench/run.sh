#!/usr/bin/env bash
# Reproduces the numbers in BENCHMARKS.md: `mvod bench --sweep` (the default grid, one fresh
# process per configuration) on the KITTI 06 and 07 clips in ../shared/data, and a long drive
# along the whole KITTI 00 ground truth rendered by mvod-synth (drift and KITTI t_rel/r_rel).
# Timing lives here, never in tests.
#
# Usage: bench/run.sh [BUILDDIR]. Tables, CSVs and plots go to BUILDDIR/bench-out/; the
# KITTI 00 render (4541 frames, ~4 min, ~360 MB) is cached in BUILDDIR/bench-cache/ (or
# MVOD_BENCH_CACHE) and reused while its mvod-synth command line is unchanged (bench/lib.sh).
# bench/instructions.sh, clips.sh, long.sh and fps.sh measure one thing each, as the latest
# sections of BENCHMARKS.md do.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
bench_init "${1:-}"
out=$build/bench-out
mkdir -p "$out"

echo "# mvod bench, $(date -u +%Y-%m-%d)"
machine
echo

# Runs mvod bench, printing the command and how long it took.
bench() {
	local name=$1
	shift
	echo "## $name"
	echo "\$ mvod bench $*"
	local t0=$SECONDS
	"$mvod" bench "$@"
	echo
	echo "($((SECONDS - t0)) s)"
	echo
}

for seq in 06 07; do
	dir=$data/kitti-odometry-$seq-clip
	if [ ! -d "$dir" ]; then
		echo "## KITTI $seq clip: $dir absent, skipped"
		continue
	fi
	bench "KITTI $seq clip, default sweep, ground-truth scale" \
		--source "kitti:$dir/sequences/$seq" --gt "$dir/poses/$seq.txt" --scale gt \
		--sweep --report "$out/kitti-$seq.md" --csv "$out/kitti-$seq.csv" \
		--plots "$out/kitti-$seq"
done

# The whole KITTI 00 path (3.7 km) through a synthetic street (bench/lib.sh's drive).
gt00=$data/kitti-groundtruth/00.txt
if [ -f "$gt00" ]; then
	k00=$(drive 00)
	# Map mode (the default), and two-view mode beside it for comparison.
	for mode in map twoview; do
		for scale in auto gt; do
			bench "mvod-synth along KITTI 00's ground truth, 4541 frames, $mode, $scale scale" \
				--source "file:$k00/video.mkv" --calib "$k00/calib.json" \
				--gt "$k00/gt.tum" --mode $mode --scale $scale \
				--report "$out/kitti00-synth-$mode-$scale.md" \
				--plots "$out/kitti00-synth-$mode-$scale"
		done
	done
else
	echo "## KITTI 00 ground truth: $gt00 absent, skipped"
fi

# Instruction counts repeat exactly where wall time does not: compare these across changes.
dir=$data/kitti-odometry-06-clip
if command -v valgrind >/dev/null && [ -d "$dir" ]; then
	for mode in map twoview; do
		echo "## callgrind, KITTI 06 clip, first 20 frames, ground-truth scale, $mode mode"
		valgrind --tool=callgrind --callgrind-out-file="$out/cg-$mode.out" "$mvod" \
			--no-lcm -q --source "kitti:$dir/sequences/06" --gt "$dir/poses/06.txt" \
			--scale gt --mode $mode --max-frames 20 \
			2>&1 | sed -n 's/.*Collected : /    instructions: /p'
		callgrind_annotate "$out/cg-$mode.out" 2>/dev/null | grep -E '^ *[0-9,]+ \(' |
			sed -n '2,6p'
	done
fi

#!/usr/bin/env bash
# Wall-clock fps in interleaved rounds, so that the machine's load falls on every column alike:
# in each round, on the KITTI 06 then 07 clip in ../shared/data, mvod's default (map mode), the
# same with --mode twoview, a base build's default (BASE) and the reference implementation
# (MVOD_REF_CMD), in that order. Each mvod run is `mvod --source kitti:CLIP --no-lcm`; its fps is
# the summary line's. fps depends on the machine and its load: compare the columns of one table
# only, and speed across changes with bench/instructions.sh.
#   --s640  the 640x480 mvod-synth street of `bench/instructions.sh --s640` instead (rendered
#           when missing) on one core (taskset -c 0), without the reference
#
# Usage: [ROUNDS=3] [BASE=MVOD] [MVOD_REF_CMD=COMMAND] bench/fps.sh [--s640] [BUILDDIR] \
#            [-- MVOD_ARGS...]
#   e.g. BASE=/work/main/build/mvod bench/fps.sh build
# MVOD_ARGS go to every mvod run. BASE: another mvod binary (say main's, against a branch's).
# MVOD_REF_CMD, when set: a command line (split at spaces) run as `COMMAND NN DIR` for each clip,
# NN = 06 or 07 and DIR = ../shared/data/kitti-odometry-NN-clip (KITTI's layout: sequences/NN,
# poses/NN.txt); it runs the reference on that clip and prints its frames a second as the last
# line of its output (and, when it prints one, its accuracy as a line err_avg=E: a line under the
# table gives it); bench/siv.sh runs the reference that way. The reference is set up outside this
# repository: nothing here installs or builds it. Prints a markdown table, also written to OUT
# (default BUILDDIR/bench-out/fps.md); the base column only with BASE.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
s640=0
if [ "${1:-}" = --s640 ]; then s640=1 && shift; fi
bench_args "$@"
out=${OUT:-$build/bench-out/fps.md}
mkdir -p "$(dirname "$out")"
ref=()
if [ -n "${MVOD_REF_CMD:-}" ] && [ $s640 = 0 ]; then read -ra ref <<<"$MVOD_REF_CMD"; fi
pin=() clips=(06 07)
if [ $s640 = 1 ]; then
	pin=(taskset -c 0) clips=(s640)
	s=$(render s640 --size 640x480 --frames 300 --codec raw)
else
	for c in "${clips[@]}"; do need "$data/kitti-odometry-$c-clip/sequences/$c"; done
fi

# fps MVOD [ARGS...]: the fps in the summary line of `MVOD --source ... ARGS`.
fps() {
	local bin=$1 src=(--source "kitti:$data/kitti-odometry-$c-clip/sequences/$c")
	shift
	[ $s640 = 1 ] && src=(--source "file:$s/video.mkv" --calib "$s/calib.json")
	"${pin[@]}" "$bin" "${src[@]}" --no-lcm "$@" "${extra[@]}" 2>&1 |
		sed -n 's/.*(\([0-9.]*\) fps).*/\1/p'
}

base=()
[ -n "${BASE:-}" ] && base=("base default")
{
	machine
	echo
	echo "| round, clip | default (map) | two-view |${base:+ ${base[*]} |} reference | default / reference |"
	echo "|---|--:|--:|${base:+--:|}--:|--:|"
} | tee "$out"
declare -A referr=()
for r in $(seq "${ROUNDS:-3}"); do
	for c in "${clips[@]}"; do
		a=$(fps "$mvod") b=$(fps "$mvod" --mode twoview) z= f=- x=-
		[ -n "${BASE:-}" ] && z=" $(fps "$BASE") |"
		if [ ${#ref[@]} -gt 0 ]; then
			o=$("${ref[@]}" "$c" "$data/kitti-odometry-$c-clip")
			f=$(tail -1 <<<"$o")
			referr[$c]=$(sed -n 's/^err_avg=//p' <<<"$o")
			x=$(awk -v a="$a" -v f="$f" 'BEGIN { printf "%.1fx", a / f }')
		fi
		lab=$c
		[ $s640 = 1 ] && lab="640x480 street, one core"
		echo "| $r, $lab | $a | $b |$z $f | $x |" | tee -a "$out"
	done
done
if [ ${#referr[@]} -gt 0 ]; then
	echo
	echo -n "The reference's err_avg (ground-truth scale, ../shared/eval.py):"
	for c in "${clips[@]}"; do echo -n " ${referr[$c]:--} on $c,"; done | sed 's/,$/./'
	echo
fi | tee -a "$out"

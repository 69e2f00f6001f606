#!/usr/bin/env bash
# make bench: measures every table of BENCHMARKS.md again with this build and checks the page
# against the measurement. Each table sits between <!-- bench:NAME --> and <!-- /bench:NAME -->;
# how a table must agree (bench/page.py) is its entry in `tables` below: exact for what is
# deterministic (trajectories: the same binary on the same input gives the same digits), but
# callgrind's instruction counts within 2 % (tol=2), wall-clock figures within a factor of 10.
# A table that disagrees is printed as a diff and fails the run (exit 1); one whose data is
# absent (../shared/data, or MVOD_DATA) is reported as skipped.
#
# Usage: bench/run.sh [--update] [--long] [-b BUILDDIR] [TABLE...]
#   --update  rewrite the tables that disagree in BENCHMARKS.md from the measurement (after a
#             deliberate change: then review `git diff BENCHMARKS.md` and commit it)
#   --long    also the long drives (table long: renders of whole KITTI ground truths, 15 minutes
#             the first time, 2 after); naming a table runs it whatever --long says
#   TABLE     only these: kitti metric synth datasets instructions headline calib photos speed
#             long (default: every one; the headline measures the two it reads)
#   -b DIR    the build (default $BUILDDIR, or build)
# The reference implementation's column of the speed table needs SIV (a checkout of it, see
# bench/siv.sh) or MVOD_REF_CMD (bench/fps.sh); without it the column says "-". Outputs go to
# BUILDDIR/bench-out/ (each table's measurement, log and diff in tables/NAME.md, .log, .diff;
# the runs behind it in NAME/), mvod-synth renders to BUILDDIR/bench-cache/.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
update=0 long=0 builddir= want=()
while [ $# -gt 0 ]; do
	case $1 in
	--update) update=1 ;;
	--long) long=1 ;;
	-b) builddir=$2 && shift ;;
	-h | --help) usage ;;
	-*) usage 2 >&2 ;;
	*) want+=("$1") ;;
	esac
	shift
done
bench_init "$builddir"
out=$build/bench-out
page=$root/BENCHMARKS.md
mkdir -p "$out"
b=$root/bench

# NAME:HOW, in the order they are measured (HOW: bench/page.py's).
tables=(kitti:exact metric:exact synth:exact datasets:exact instructions:tol=2 headline:tol=2
	calib:exact photos:exact speed:order long:exact)

t_kitti() { OUT=$out/kitti "$b/clips.sh" "$build"; }

# The clips in height and external scale, then mvod-synth's street.
t_metric() {
	OUT=$out/metric FE=klt SCALES="height external external-noise external-bias" \
		"$b/clips.sh" "$build" || return
	OUT=$out/metric-street CASES=street SCALES="height external external-noise" \
		"$b/synth.sh" "$build" | tail -n +3
}

t_synth() { OUT=$out/synth "$b/synth.sh" "$build"; }

t_datasets() { OUT=$out/datasets CASES="mkv png euroc tum tum-mono kitti-raw" "$b/synth.sh" "$build"; }

t_long() { OUT=$out/long SCALES="auto height external" "$b/long.sh" "$build"; }

t_calib() { OUT=$out/calib CASES="charuco chessboard fisheye" "$b/calib.sh" "$build"; }

t_photos() { OUT=$out/calib CASES="photos-chessboard photos-charuco" "$b/calib.sh" "$build"; }

# The machine, the clips' rounds, the one-core rounds, then the reference's accuracy.
t_speed() {
	local ref=${MVOD_REF_CMD:-${SIV:+$b/siv.sh}} clips
	clips=$(OUT=$out/speed/clips.md MVOD_REF_CMD=$ref "$b/fps.sh" "$build") || return
	grep -v -e '^The reference' <<<"$clips" | sed '${/^$/d}'
	OUT=$out/speed/s640.md "$b/fps.sh" --s640 "$build" | grep '^| [0-9]'
	grep '^The reference' <<<"$clips" | sed 's/^/\n/' || true
}

# One row each: LABEL|bench/instructions.sh's options|mvod's, two callgrind runs at a time.
instr_rows=(
	"default (map mode, KLT, free scale), KITTI 06 clip, frames 3-51|--clip 06 --whole|"
	"default, KITTI 07 clip, frames 3-160|--clip 07 --whole|"
	"--mode twoview, KITTI 06 clip, frames 3-51|--clip 06 --whole|--mode twoview"
	"--mode twoview, KITTI 07 clip, frames 3-160|--clip 07 --whole|--mode twoview"
	"--frontend orb (map mode), KITTI 06 clip, frames 3-20|--clip 06|--frontend orb"
	"default, 640x480 mvod-synth street (uncompressed), frames 51-300|--s640|"
)
t_instructions() {
	local i row opts args
	(need "$data/kitti-odometry-06-clip" "$data/kitti-odometry-07-clip") || return
	for i in "${!instr_rows[@]}"; do
		IFS='|' read -r _ opts args <<<"${instr_rows[$i]}"
		# shellcheck disable=SC2086 # the options and arguments are words
		spawn env OUT="$out/instructions" TAG="row$i" "$b/instructions.sh" $opts "$build" -- $args \
			>"$out/instructions/row$i" 2>&1
	done
	wait
	echo "| run | instructions a frame |"
	echo "|---|--:|"
	for i in "${!instr_rows[@]}"; do
		row=$out/instructions/row$i
		grep -q 'absent: skipped' "$row" && { cat "$row" >&2 && return 77; } # no valgrind
		grep -q 'instructions a frame' "$row" || { cat "$row" >&2 && return 1; }
		echo "| ${instr_rows[$i]%%|*} | $(cut -d' ' -f1 "$row") |"
	done
}

# The mission's figures at mvod's defaults on the real clips, from the kitti and instructions
# tables' runs.
t_headline() {
	measure kitti && measure instructions || return 77
	local k=$out/kitti/klt-map i=$out/instructions/row
	echo "| at the defaults (map mode, KLT, 500 tracks) | KITTI 06 clip | KITTI 07 clip | mission |"
	echo "|---|--:|--:|--:|"
	echo "| err_avg, ground-truth scale | $(col "$k-gt-06.row" err_avg) |" \
		"$(col "$k-gt-07.row" err_avg) | 0.08 (Python reference 0.26) |"
	echo "| free scale: Sim(3) ATE, % of the path | $(col "$k-auto-06.row" ate_pct) |" \
		"$(col "$k-auto-07.row" ate_pct) | 0.3 (DSO 0.45) |"
	echo "| camera height 1.65 m: SE(3) ATE, % of the path | $(col "$k-height-06.row" ate_pct) |" \
		"$(col "$k-height-07.row" ate_pct) | 0.4 |"
	echo "| instructions a frame (callgrind, whole clip) | $(cut -d' ' -f1 "${i}0") |" \
		"$(cut -d' ' -f1 "${i}1") | under 50e6 |"
}

declare -A status=()
# measure NAME: measures table NAME once (its generator's stdout into tables/NAME.md), checks or
# updates the page, sets status[NAME]; returns 0 when the table was measured.
measure() {
	local name=$1 how t0=$SECONDS rc=0
	[ -n "${status[$name]:-}" ] && { [ "${status[$name]}" != skipped ]; return; }
	how=$(printf '%s\n' "${tables[@]}" | sed -n "s/^$name://p")
	mkdir -p "$out/tables" "$out/$name"
	"t_$name" >"$out/tables/$name.md" 2>"$out/tables/$name.log" || rc=$?
	if [ $rc = 77 ]; then
		status[$name]=skipped
		echo >&3 "$name: skipped ($(grep -m1 absent "$out/tables/$name.log" | sed 's/: skipped//' ||
			echo "its data is absent"))"
		return 1
	elif [ $rc != 0 ]; then
		status[$name]=failed
		echo >&3 "$name: FAILED to measure (exit $rc), $((SECONDS - t0)) s:"
		tail -n 20 "$out/tables/$name.log" >&3
		return 0
	fi
	if python3 "$b/page.py" "$([ $update = 1 ] && echo update || echo check)" "$page" "$name" \
		"$how" <"$out/tables/$name.md" >"$out/tables/$name.diff"; then
		status[$name]=ok
		[ -s "$out/tables/$name.diff" ] && status[$name]=updated
	else
		status[$name]=differs
	fi
	echo >&3 "$name: ${status[$name]} ($how, $((SECONDS - t0)) s)"
	[ "${status[$name]}" = ok ] || cat "$out/tables/$name.diff" >&3
	# Wall-clock figures are this run's: shown whatever the page says.
	[ $name != speed ] || cat "$out/tables/$name.md" >&3
}

# Every block of the page has its table here, and every table its block.
names=$(python3 "$b/page.py" names "$page")
for t in "${tables[@]}"; do
	grep -qx "${t%%:*}" <<<"$names" || { echo "run.sh: BENCHMARKS.md has no block ${t%%:*}" && exit 1; }
done
for n in $names; do
	printf '%s\n' "${tables[@]}" | grep -q "^$n:" || { echo "run.sh: no table measures block $n" && exit 1; }
done
for n in "${want[@]}"; do
	printf '%s\n' "${tables[@]}" | grep -q "^$n:" || { echo "run.sh: no table $n" >&2 && exit 2; }
done

exec 3>&1 # measure's report, also from inside a table that measures another
machine
t0=$SECONDS
for t in "${tables[@]}"; do
	name=${t%%:*}
	if [ ${#want[@]} -gt 0 ]; then
		printf '%s\n' "${want[@]}" | grep -qx "$name" || continue
	elif [ $name = long ] && [ $long = 0 ]; then
		continue
	fi
	measure "$name" || true
done
bad=$(for n in "${!status[@]}"; do echo "${status[$n]}"; done | grep -c -E 'differs|failed' || true)
echo "make bench: ${#status[@]} tables in $(((SECONDS - t0 + 30) / 60)) min:" \
	"$(for n in "${!status[@]}"; do echo "$n ${status[$n]}"; done | sort | paste -sd, | sed 's/,/, /g')"
[ "$bad" = 0 ] || { echo "make bench: $bad tables disagree with BENCHMARKS.md" \
	"(bench/run.sh --update rewrites them after a deliberate change)" && exit 1; }

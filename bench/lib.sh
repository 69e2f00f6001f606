# Shared by the bench/ scripts (sourced, not run).
#
# bench_init BUILDDIR sets root (the repository), build (BUILDDIR, default $BUILDDIR or build),
# mvod and synth (the binaries in it), data (${MVOD_DATA:-$root/../shared/data}, resolved) and
# cache (${MVOD_BENCH_CACHE:-BUILDDIR/bench-cache}: mvod-synth renders, kept between runs).

bench_init() {
	root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
	build=${1:-${BUILDDIR:-build}}
	mvod=$build/mvod
	synth=$build/tools/mvod-synth
	data=${MVOD_DATA:-$root/../shared/data}
	# Resolved, so that a render's recorded command line is the same from every worktree.
	[ -d "$data" ] && data=$(cd "$data" && pwd -P)
	cache=${MVOD_BENCH_CACHE:-$build/bench-cache}
	if [ ! -x "$mvod" ]; then
		echo "$mvod: not built (meson setup $build && meson compile -C $build)" >&2
		exit 1
	fi
}

# bench_args ARGS...: the scripts' command line, [BUILDDIR] [-- EXTRA...]: bench_init BUILDDIR
# and extra=(EXTRA...); -h or --help prints the usage.
bench_args() {
	local b=
	case ${1:-} in -h | --help) usage ;; --) ;; -*) usage 2 >&2 ;; *) b=${1:-} && shift $(($# > 0)) ;; esac
	if [ "${1:-}" = -- ]; then shift; fi
	extra=("$@")
	bench_init "$b"
}

# machine: one line on the machine and the build (say it beside any wall-clock figure).
machine() {
	echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores," \
		"$(free -g | awk '/^Mem:/ {print $2}') GiB; $(uname -sr); load $(cut -d' ' -f1-3 \
		/proc/loadavg); OpenCV $(pkg-config --modversion opencv4); $(gcc --version | head -1);" \
		"$("$mvod" --version)"
}

# usage: prints the calling script's top comment (its usage) and exits.
usage() {
	sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
	exit "${1:-0}"
}

# need PATH...: exits 77 (skipped, as meson's tests do) naming the first PATH that is absent.
need() {
	local p
	for p; do
		if [ ! -e "$p" ]; then
			echo "$p absent: skipped (set MVOD_DATA to the folder holding the data)" >&2
			exit 77
		fi
	done
}

# render NAME ARGS...: prints the folder $cache/NAME holding `mvod-synth ARGS`, rendering it
# first unless it holds exactly that already (its file `args` records the command line). A
# render is written beside it and renamed when whole, so an interrupted one is never reused.
render() {
	local dir=$cache/$1
	shift
	if [ "$(cat "$dir/args" 2>/dev/null)" != "$*" ]; then
		echo "rendering mvod-synth $* into $dir" >&2
		rm -rf "$dir" "$dir.part"
		mkdir -p "$cache"
		"$synth" --out "$dir.part" "$@" >&2
		echo "$*" >"$dir.part/args"
		mv "$dir.part" "$dir"
	fi
	echo "$dir"
}

# drive NN: render (as above) of a drive along the whole KITTI NN ground truth in ../shared/data
# through mvod-synth's street at KITTI's field of view (fx 707 px at 1226 px wide, so 369 px at
# 640) and a quarter of its pixels; with FULL=1 at KITTI's own size instead (1240x376, fx 707:
# what the rules for frames 1024 px wide or more see, 3-4 times the time and the disk); exits
# 77 when that ground truth is absent.
drive() {
	local gt=$data/kitti-groundtruth/$1.txt
	need "$gt"
	local size=640x192 fx=369
	[ "${FULL:-0}" = 1 ] && size=1240x376 fx=707
	render "kitti$1-$size" --path "$gt" --size $size --fx $fx --format mkv
}

# spawn CMD...: runs CMD in the background, at most ${JOBS:-2} at once; `wait` for the last.
spawn() {
	while [ "$(jobs -rp | wc -l)" -ge "${JOBS:-2}" ]; do
		wait -n || true
	done
	"$@" &
}

# bench_row FILE ARGS...: `mvod bench ARGS`, its output (table row, CSV, log) into FILE.
bench_row() {
	local file=$1
	shift
	"$mvod" bench "$@" >"$file" 2>&1 || echo "mvod bench $* failed: see $file" >&2
}

# scale_args NAME SCALE: sets sargs to the mvod arguments of SCALE: gt, auto, height
# (--camera-height $cam_height), external (the exact speed of the ground truth $gt, times from
# $times when it is KITTI's, written by `mvod speed-log` into $out/NAME.speed.lcmlog),
# external-noise (that speed times 1 + 5 % N(0, 1), seed 1) or external-bias (2 % too fast).
scale_args() {
	local log=$out/$1.speed.lcmlog mk=()
	case $2 in
	external*)
		mk=("$mvod" speed-log "$gt" "$log" ${times:+--times "$times"})
		case $2 in
		external-noise) mk+=(--noise 0.05 --seed 1) ;;
		external-bias) mk+=(--bias 0.02) ;;
		esac
		"${mk[@]}" >/dev/null
		sargs=(--scale external --speed-url "file://$log?mode=r") ;;
	height) sargs=(--scale height --camera-height "$cam_height") ;;
	*) sargs=(--scale "$2") ;;
	esac
}

# run_bench NAME SCALE ARGS...: bench_row in the background (spawn) of `mvod bench ARGS` with
# SCALE's arguments (scale_args), extra and a trajectory, into $out/NAME.row and .traj, and
# NAME appended to runs; with DRAWS="480 500 520", once for each of those --tracks counts
# (named NAME-tN).
run_bench() {
	local name=$1 scale=$2 t tracks run
	shift 2
	for t in ${DRAWS:--}; do
		tracks=() run=$name
		[ "$t" != - ] && tracks=(--tracks "$t") && run=$name-t$t
		runs+=("$run")
		scale_args "$run" "$scale"
		spawn bench_row "$out/$run.row" "$@" "${sargs[@]}" "${tracks[@]}" \
			--trajectory "$out/$run.traj" --log-level warn "${extra[@]}"
	done
}

# The accuracy columns of the tables (mvod bench's CSV names) and their titles.
acc_titles="err_avg|RPE rot deg|RPE dir deg|RPE trans %|ATE m|ATE %|scale drift"
acc_cols=(err_avg rpe_rot_deg rpe_dir_deg rpe_trans_pct ate_m ate_pct scale_drift)

# col FILE NAME: column NAME (as in the CSV header: t_rel_pct, scale_drift, ...) of the last
# row `mvod bench` printed into FILE; "-" when there is none.
col() {
	awk -F, -v name="$2" '
		$1 == "detector" {
			c = 0
			for (i = 1; i <= NF; i++) if ($i == name) c = i
			if (c && getline > 0) v = $c
		}
		END { print (v == "" ? "-" : v) }' "$1"
}

# cols FILE NAME...: col for each NAME, the values joined by " | ".
cols() {
	local f=$1 out= name
	shift
	for name; do out+="${out:+ | }$(col "$f" "$name")"; done
	echo "$out"
}

# runs_table "TITLE|TITLE..." NAME...: a markdown table of the runs named in the array runs
# (their $out/RUN.row): a row each, the run's name, then cols NAME..., under the titles.
runs_table() {
	local titles=$1 run
	shift
	echo "| run | ${titles//|/ | } |"
	printf '|---|' && printf -- '--:|%.0s' "$@" && echo
	for run in "${runs[@]}"; do
		echo "| $run | $(cols "$out/$run.row" "$@") |"
	done
}

# draw_means: a runs_table on stdin into the same table of each run's mean over its draws (the
# runs NAME-tN of DRAWS are NAME's), "-" values left out.
draw_means() {
	awk -F' *[|] *' 'NR <= 2 { print; next }
		{ r = $2; sub(/-t[0-9]+$/, "", r); if (!(r in seen)) { seen[r]; order[k++] = r }
		  nf = NF; for (i = 3; i < NF; i++) if ($i != "-") { s[r, i] += $i; m[r, i]++ } }
		END { for (j = 0; j < k; j++) { r = order[j]; line = "| " r
			for (i = 3; i < nf; i++)
				line = line sprintf(" | %s", m[r, i] ? sprintf("%.4g", s[r, i] / m[r, i]) : "-")
			print line " |" } }'
}

#!/usr/bin/env bash
# Behaviour check for refactors: runs two mvod binaries (say main's and a branch's) on the same
# inputs and compares every output. Trajectories (TUM, KITTI), --plot PNGs and mvod bench's
# plots must be byte-identical. What depends on the wall clock is compared without it:
#   - LCM logs: every mvod.pose_t payload byte for byte, in order; of mvod.status_t, the
#     sequence of (state, faults) changes and the last message's counters (utime, state,
#     features, matches, inliers, frames, dropped, faults). fps, stage milliseconds, rss_kb and
#     uptime_s are timings, and periodic status messages come at wall-clock moments.
#   - mvod bench CSV: every column except fps and the *_ms timing columns.
#
# Usage: bench/identical.sh OLD_MVOD NEW_MVOD [MVOD_SYNTH]
#   e.g. bench/identical.sh ../main/build/mvod build/mvod
# Inputs: the KITTI 06 and 07 clips in ../shared/data (skipped when absent) and short
# mvod-synth sequences. On each input: the default run (LCM log, plot), --scale gt, mvod
# bench, and the matrix of both modes (map, twoview) x both front ends (klt, orb) x every scale
# mode (auto, gt, height, external: the ground truth's speed through a file:// LCM log made
# by NEW_MVOD speed-log, the same log for both binaries; the external rows are skipped when
# NEW_MVOD has no speed-log); then two-view with SIFT and with FLANN on the turn. MATRIX=0 runs only the
# default rows. Outputs go to a temporary folder, removed at the end unless KEEP=1. Prints one
# line per comparison and exits 1 when any output differs.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
synth=${3:-$(dirname "$2")/tools/mvod-synth}
data=${MVOD_DATA:-$root/../shared/data}
work=$(mktemp -d)
[ "${KEEP:-0}" = 1 ] && echo "outputs in $work" || trap 'rm -rf "$work"' EXIT
# Copies, so that a rebuild during the run does not swap a binary under it.
cp "$1" "$work/mvod.old" && cp "$2" "$work/mvod.new" && cp "$synth" "$work/mvod-synth"
old=$work/mvod.old new=$work/mvod.new synth=$work/mvod-synth
speedlog=
"$new" speed-log --help >/dev/null 2>&1 && speedlog=$new
fail=0

# Decodes an LCM log into what must not change (see above), one line per item.
lcm_digest() {
	python3 - "$1" <<'EOF'
import struct, sys, hashlib
data = open(sys.argv[1], 'rb').read()
off, changes, last, last2 = 0, [], None, None
while off < len(data):
	sync, _, _, clen, dlen = struct.unpack_from('>IqqII', data, off)
	assert sync == 0xEDA1DA01, 'not an LCM log'
	off += 28
	chan = data[off:off + clen].decode()
	payload = data[off + clen:off + clen + dlen]
	off += clen + dlen
	if chan == 'MVOD_POSE':
		print('pose', hashlib.sha256(payload).hexdigest())
	elif chan == 'MVOD_STATUS':
		# fingerprint, utime, state, fps, 5 stage ms, features, matches, inliers, frames,
		# dropped, rss_kb, uptime_s, faults
		f = struct.unpack_from('>qqbffffffiiiqqqdi', payload)
		key = (f[2], f[-1])
		if not changes or changes[-1] != key:
			changes.append(key)
		last = (f[1], f[2], f[9], f[10], f[11], f[12], f[13], f[-1])
	elif chan == 'MVOD_STATUS2':
		# status_t's fields, then map_points, keyframes, scale, scale_confidence, latency_ms:
		# the last message's map counts and scale (latency is a timing)
		f = struct.unpack_from('>qqbffffffiiiqqqdiiidff', payload)
		last2 = (f[1], f[2], f[9], f[10], f[11], f[12], f[13], f[16], f[17], f[18], f[19], f[20])
	else:
		print('channel', chan, hashlib.sha256(payload).hexdigest())
print('status changes (state, faults)', changes)
print('last status', last)
print('last status2', last2)
EOF
}

# The bench CSV without its timing columns.
csv_digest() {
	python3 - "$1" <<'EOF'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
keep = [i for i, h in enumerate(rows[0]) if h != 'fps' and not h.endswith('_ms') and
	'ms' not in h.split('_')]
for r in rows:
	print(','.join(r[i] for i in keep))
EOF
}

same() { # NAME FILE_OLD FILE_NEW [digest]
	local name=$1 a=$2 b=$3 how=${4:-}
	if [ ! -f "$a" ] || [ ! -f "$b" ]; then
		echo "DIFFERENT $name (only one build wrote it)"
		fail=1
		return
	fi
	if [ -n "$how" ]; then
		"$how" "$a" >"$a.digest" && "$how" "$b" >"$b.digest"
		a=$a.digest b=$b.digest
	fi
	if cmp -s "$a" "$b"; then
		echo "same      $name${how:+ ($how)}"
	else
		echo "DIFFERENT $name${how:+ ($how)}"
		fail=1
	fi
}

# run CASE ARGS...: both binaries, outputs named old.* and new.* in $work/CASE.
run() {
	local case=$1
	shift
	mkdir -p "$work/$case"
	for side in old new; do
		local bin=$old
		[ $side = new ] && bin=$new
		local o=$work/$case/$side
		"$bin" "${@//@OUT@/$o}" -q >"$o.stdout" 2>"$o.stderr" || echo "$case: $side exited $?" \
			>>"$work/$case/exit"
	done
	[ -f "$work/$case/exit" ] && { cat "$work/$case/exit"; fail=1; }
	for f in "$work/$case"/old.*; do
		case $f in *.stdout | *.stderr | *.digest | *.plots) continue ;; esac
		local suffix=${f##*/old.} how=
		case $suffix in lcmlog) how=lcm_digest ;; csv) how=csv_digest ;; esac
		same "$case/$suffix" "$f" "$work/$case/new.$suffix" $how
	done
	if [ -d "$work/$case/old.plots" ]; then
		for f in "$work/$case/old.plots"/*; do
			same "$case/plots/${f##*/}" "$f" "$work/$case/new.plots/${f##*/}"
		done
	fi
}

# matrix CASE SPEED_URL ARGS...: ARGS (source, calibration, ground truth) in both modes, both
# front ends and every scale mode, each writing a TUM trajectory; SPEED_URL empty: no external.
matrix() {
	local case=$1 speed=$2
	shift 2
	[ "${MATRIX:-1}" = 1 ] || return 0
	for mode in map twoview; do
		for fe in klt orb; do
			for scale in auto gt height external; do
				local extra=(--no-lcm)
				if [ $scale = external ]; then
					[ -n "$speed" ] || continue
					extra=(--no-lcm --speed-url "$speed")
				fi
				[ $scale = height ] && extra+=(--camera-height 1.65)
				run "$case-$mode-$fe-$scale" "$@" --mode $mode --frontend $fe --scale $scale \
					"${extra[@]}" --trajectory @OUT@.tum
			done
		done
	done
}

# speed_url NAME GT [--times FILE]: an LCM log of GT's exact speed, its file:// URL printed.
speed_url() {
	[ -n "$speedlog" ] || return 0
	local log=$work/$1.speed.lcmlog
	shift
	"$speedlog" speed-log "$@" "$log" >/dev/null && echo "file://$log?mode=r"
}

# Two short street sequences: the turn (rotation and translation) as video, the forward path
# as PNG images, so both file sources are covered.
"$synth" --path turn --frames 60 --speed 3 --out "$work/turn" >/dev/null
"$synth" --path forward --frames 40 --format png --out "$work/fwd" >/dev/null
for s in turn fwd; do
	src=file:$work/turn/video.mkv
	[ $s = fwd ] && src=images:$work/fwd/images
	common=(--source "$src" --calib "$work/$s/calib.json")
	run "$s-free" "${common[@]}" --gt "$work/$s/gt.tum" --trajectory @OUT@.tum \
		--plot @OUT@.png --status-rate 0.1 --lcm-url "file://@OUT@.lcmlog?mode=w"
	run "$s-gt" "${common[@]}" --gt "$work/$s/gt.tum" --scale gt --trajectory @OUT@.kitti \
		--plot @OUT@.png --no-lcm
	run "$s-bench" bench "${common[@]}" --gt "$work/$s/gt.tum" --csv @OUT@.csv \
		--plots @OUT@.plots
	matrix "$s" "$(speed_url "$s" "$work/$s/gt.tum")" "${common[@]}" --gt "$work/$s/gt.tum"
done
if [ "${MATRIX:-1}" = 1 ]; then
	turn=(--source "file:$work/turn/video.mkv" --calib "$work/turn/calib.json" --gt "$work/turn/gt.tum")
	run turn-twoview-sift "${turn[@]}" --mode twoview --detector sift --no-lcm --trajectory @OUT@.tum
	run turn-twoview-flann "${turn[@]}" --mode twoview --frontend orb --matcher flann-ratio \
		--no-lcm --trajectory @OUT@.tum
fi
for seq in 06 07; do
	dir=$data/kitti-odometry-$seq-clip
	if [ ! -d "$dir" ]; then
		echo "skipped   kitti-$seq: $dir absent"
		continue
	fi
	kitti=(--source "kitti:$dir/sequences/$seq" --gt "$dir/poses/$seq.txt")
	run "kitti$seq-free" "${kitti[@]}" --trajectory @OUT@.tum --plot @OUT@.png \
		--status-rate 0.1 --lcm-url "file://@OUT@.lcmlog?mode=w"
	run "kitti$seq-gt" "${kitti[@]}" --scale gt --trajectory @OUT@.kitti --no-lcm
	run "kitti$seq-bench" bench "${kitti[@]}" --scale gt --csv @OUT@.csv --plots @OUT@.plots
	matrix "kitti$seq" "$(speed_url "kitti$seq" "$dir/poses/$seq.txt" --times \
		"$dir/sequences/$seq/times.txt")" "${kitti[@]}"
done
[ $fail = 0 ] && echo "identical: every output the same" || echo "identical: outputs differ"
exit $fail

#!/bin/sh
# make demo's closing summary names what new code should subscribe to (issue 38: it named the
# v1 mvod.pose_t on MVOD_POSE while the README tells new code to use pose2_t on MVOD_POSE2).
# Read from `make -n demo` (nothing runs): every "mvod.TYPE on CHANNEL" of its LCM log line
# must be a type of lcmtypes/ that no newer version supersedes (NAME_t by NAME2_t), on the
# channel mvod publishes it on: --print-config's NAME-channel, with 2 appended for a v2 type.
# The pose must be among them. MVOD_SRCDIR and MVOD are set by meson test.
set -eu
src=${MVOD_SRCDIR:?run through meson test}
mvod=${MVOD:?run through meson test}
fail=0

line=$(make -n -s -C "$src" demo 2>/dev/null | grep 'demo: LCM log' || true)
pairs=$(echo "$line" | grep -o 'mvod\.[a-z0-9_]* on [A-Za-z0-9_]*' || true)
[ -n "$pairs" ] || { echo "make demo's LCM log line names no 'mvod.TYPE on CHANNEL': $line"; exit 1; }
config=$("$mvod" --print-config)
echo "$pairs" | {
	while read -r pair; do
		type=${pair#mvod.}
		type=${type%% on *}
		chan=${pair##* on }
		name=${type%_t}
		family=${name%2}
		if [ ! -f "$src/lcmtypes/$type.lcm" ]; then
			echo "make demo names mvod.$type, which lcmtypes/ does not define"
			fail=1
			continue
		fi
		if [ "$family" = "$name" ] && [ -f "$src/lcmtypes/${family}2_t.lcm" ]; then
			echo "make demo names mvod.$type, which mvod.${family}2_t supersedes"
			fail=1
		fi
		want=$(echo "$config" | sed -n "s/^$family-channel = //p")
		[ "$family" = "$name" ] || want=${want}2
		if [ "$chan" != "$want" ]; then
			echo "make demo names mvod.$type on $chan; mvod publishes it on ${want:-no channel}"
			fail=1
		fi
	done
	exit $fail
} || fail=1
echo "$pairs" | grep -q '^mvod\.pose2_t on ' || { echo "make demo does not name mvod.pose2_t"; fail=1; }
[ $fail = 0 ] && echo "demo_summary: $(echo "$pairs" | tr '\n' ';')"
exit $fail

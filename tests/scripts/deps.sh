#!/bin/sh
# What the Makefile would install, read from `make -n` (nothing runs): `make demo` (through
# make deps) installs no test tool, no libcamera-dev and no Ceres (map mode's bundle adjustment
# is mvod's own; Ceres is the tests' reference); `make test` installs the test
# toolchain; LIBCAMERA=1 adds libcamera-dev; and the dependency table of docs/building.md names
# every package either installs (issue 18). MVOD_SRCDIR is the source tree (set by meson test).
set -eu
src=${MVOD_SRCDIR:?run through meson test}
fail=0

# The packages the apt step of `make -n TARGET [VAR=...]` checks for, one per line.
pkgs() {
	make -n -s -C "$src" "$@" 2>/dev/null | grep -o 'for p in [^;]*;' | sed 's/^for p in //; s/;$//' |
		tr ' ' '\n' | grep -v '^$' | sort -u
}

demo=$(pkgs demo)
testing=$(pkgs test)
camera=$(pkgs deps LIBCAMERA=1)
[ -n "$demo" ] || { echo "make -n demo shows no apt step"; exit 1; }
for p in libcmocka-dev clang libclang-rt-14-dev valgrind libcamera-dev libceres-dev; do
	if echo "$demo" | grep -qx "$p"; then
		echo "make demo would install $p, which running mvod does not need"
		fail=1
	fi
done
for p in libcmocka-dev clang libclang-rt-14-dev valgrind libceres-dev gcc libopencv-dev; do
	echo "$testing" | grep -qx "$p" || { echo "make test would not install $p"; fail=1; }
done
echo "$camera" | grep -qx libcamera-dev || { echo "make deps LIBCAMERA=1 misses libcamera-dev"; fail=1; }
# What running needs comes with demo: what make deps alone installs.
for p in libopencv-contrib-dev zlib1g-dev liblcm-bin; do
	echo "$demo" | grep -qx "$p" || { echo "make demo would not install $p"; fail=1; }
done
for p in $testing libcamera-dev; do
	grep -q "^| .*\`$p\`" "$src/docs/building.md" ||
		{ echo "docs/building.md's dependency table does not name $p"; fail=1; }
done
[ $fail = 0 ] && echo "deps: demo installs $(echo $demo | wc -w) packages, test $(echo $testing | wc -w)"
exit $fail

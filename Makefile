# Thin wrapper around meson: the two commands a new user runs are `make demo` and `make test`.
BUILDDIR ?= build
ASANDIR  ?= build-asan
FUZZDIR  ?= build-fuzz
# Seconds of fuzzing per target: make fuzz (FUZZ_SECONDS=600 make fuzz for a long run).
FUZZ_SECONDS ?= 60
DEMODIR  ?= demo-out
PREFIX   ?= /usr/local
DESTDIR  ?=

# Debian 12 packages. `make deps` (and so `make`, `make demo`, `make install`) installs what
# building and running mvod need, nothing more: on a Pi's SD card or a robot offline for long,
# the test tools are dead weight. `make test` adds the test toolchain (make deps-test).
# libcamera-dev only on request (make deps LIBCAMERA=1): meson builds the libcamera: source
# when it is installed (-Dlibcamera=auto) and goes on without it.
DEBS_RUN := gcc g++ make pkg-config meson ninja-build \
	libopencv-dev libopencv-contrib-dev liblcm-dev liblcm-bin libglib2.0-dev libcjson-dev \
	libyaml-dev libxml2-dev libjpeg62-turbo-dev libavformat-dev libavcodec-dev libavutil-dev \
	libswscale-dev zlib1g-dev \
	libinih-dev libsystemd-dev libdeflate-dev
# cmocka: the test suites; clang and its runtime: libFuzzer; valgrind: the memcheck test;
# Ceres (with Eigen, glog, SuiteSparse): the reference unit/ba compares bundle adjustment with.
DEBS_TEST := libcmocka-dev clang libclang-rt-14-dev valgrind libceres-dev
DEBS_LIBCAMERA := libcamera-dev
DEBS := $(DEBS_RUN) $(if $(LIBCAMERA),$(DEBS_LIBCAMERA))

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: all deps deps-test build test test-asan test-fuzz fuzz fuzz-run mutate demo bench install \
	clean cross-arm64

all: build

# Installs those of the packages $(1) that are missing (apt; sudo when not root).
define apt_missing
	@missing=""; \
	for p in $(1); do \
		dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || \
			missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
		echo "make $@: installing$$missing"; \
		$(SUDO) apt-get update -qq && \
		$(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
			--no-install-recommends $$missing; \
	fi
endef

deps:
	$(call apt_missing,$(DEBS))

deps-test: deps
	$(call apt_missing,$(DEBS_TEST))

$(BUILDDIR)/build.ninja:
	meson setup $(BUILDDIR) --prefix=$(PREFIX)

$(ASANDIR)/build.ninja:
	meson setup $(ASANDIR) -Dbuildtype=debugoptimized -Db_sanitize=address,undefined -Dtests=enabled \
		-Db_lundef=false

# clang with libFuzzer: the library under AddressSanitizer and coverage, the targets linked to
# libFuzzer's main. No camera backend is fuzzed, so libcamera stays out.
$(FUZZDIR)/build.ninja:
	CC=clang CXX=clang++ meson setup $(FUZZDIR) -Dfuzz=true -Dbuildtype=debugoptimized \
		-Db_sanitize=address -Db_lundef=false -Dlibcamera=disabled \
		-Dc_args=-fsanitize=fuzzer-no-link -Dcpp_args=-fsanitize=fuzzer-no-link

# Whether clang can link a libFuzzer target here (clang and libclang-rt-14-dev installed).
HAVE_LIBFUZZER = echo 'int LLVMFuzzerTestOneInput(const char *d, long n) { return 0; }' | \
	clang -fsanitize=fuzzer -x c - -o /dev/null 2>/dev/null

build: deps $(BUILDDIR)/build.ninja
	meson compile -C $(BUILDDIR)

# Every suite (unit, integration, data), then the unit and integration suites again under
# AddressSanitizer and UndefinedBehaviorSanitizer, then each fuzz target for a few seconds.
# -Dtests=enabled: a build dir set up by make demo (before cmocka was there) gets its tests.
test: deps-test build
	meson configure $(BUILDDIR) -Dtests=enabled
	meson compile -C $(BUILDDIR)
	meson test -C $(BUILDDIR) --print-errorlogs
	$(MAKE) --no-print-directory test-asan
	$(MAKE) --no-print-directory test-fuzz

# The timeouts are set for the release build; AddressSanitizer and UBSan run it 2-3 times slower
# (integration/synth_vo: 231 s release, over 600 s sanitized on 2 busy cores), hence twice them.
test-asan: deps-test $(ASANDIR)/build.ninja
	meson compile -C $(ASANDIR)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
	UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
		meson test -C $(ASANDIR) --suite unit --suite integration --print-errorlogs \
		--timeout-multiplier 2

# The regression inputs of fuzz/corpus/ and 50000 fuzzing runs from a fixed seed per target, so
# the result is the same on every machine; skipped without clang. `make fuzz` explores instead.
test-fuzz:
	@if $(HAVE_LIBFUZZER); then $(MAKE) --no-print-directory fuzz-run FUZZ_ENV=; \
	else echo "test-fuzz: skipped: clang cannot link libFuzzer (make deps installs it)"; fi

fuzz:
	@$(MAKE) --no-print-directory fuzz-run FUZZ_ENV=MVOD_FUZZ_SECONDS=$(FUZZ_SECONDS)

# On failure, what libFuzzer reported and each crashing input (base64) come last, where a CI log's
# tail shows them.
fuzz-run: deps-test $(FUZZDIR)/build.ninja
	meson compile -C $(FUZZDIR)
	@$(FUZZ_ENV) meson test -C $(FUZZDIR) --suite fuzz --print-errorlogs || { \
		grep -h -E '^(==[0-9]+==ERROR|SUMMARY|ERROR: libFuzzer|    #[0-9] )' \
			$(FUZZDIR)/meson-logs/testlog.txt | head -n 40; \
		for f in $(FUZZDIR)/fuzz/*-crash-* $(FUZZDIR)/fuzz/*-leak-* $(FUZZDIR)/fuzz/*-oom-* \
			$(FUZZDIR)/fuzz/*-timeout-*; do \
			[ -f "$$f" ] && echo "$$f (base64): $$(head -c 3000 "$$f" | base64 -w0)"; \
		done; exit 1; }

# Mutation testing: each edit in tests/mutate/mutations.txt applied to a scratch copy of this
# tree, built, and run against the tests that must catch it; exit 1 if one survives. Minutes,
# not part of make test. MUTATE=substring runs only the matching mutations.
mutate: deps-test
	tests/mutate/run.py $(MUTATE)

demo: build
	@rm -rf $(DEMODIR) && mkdir -p $(DEMODIR)
	$(BUILDDIR)/tools/mvod-synth --path turn --frames 150 --speed 3 --codec raw --out $(DEMODIR)/synth
	$(BUILDDIR)/mvod --source file:$(DEMODIR)/synth/video.mkv --calib $(DEMODIR)/synth/calib.json \
		--gt $(DEMODIR)/synth/gt.tum --trajectory $(DEMODIR)/trajectory.tum \
		--plot $(DEMODIR)/trajectory.png \
		--lcm-url 'file://$(abspath $(DEMODIR))/mvod.lcmlog?mode=w'
	$(BUILDDIR)/mvod view --lcm-url 'file://$(abspath $(DEMODIR))/mvod.lcmlog?mode=r&speed=0' \
		--png $(DEMODIR)/view.png
	@echo
	@echo "demo: trajectory  $(DEMODIR)/trajectory.tum (TUM: t x y z qx qy qz qw)"
	@echo "demo: plot        $(DEMODIR)/trajectory.png"
	@echo "demo: LCM log     $(DEMODIR)/mvod.lcmlog (mvod.pose2_t on MVOD_POSE2, mvod.status2_t on MVOD_STATUS2)"
	@echo "demo: viewer      $(DEMODIR)/view.png (mvod view of that log: path, heading, state, rates)"
	@echo "demo: input       $(DEMODIR)/synth/ (video.mkv, calib.json, gt.tum, gt.kitti)"

# arm64 (Raspberry Pi 4/5, Jetson): Debian's cross toolchain compiles every C file of src/ for
# arm64, and the unit tests whose code needs neither OpenCV nor LCM (the Hamming distance of
# matching, the capture mailbox, geometry) are built for arm64 and run under qemu-user. Debian
# 12 cannot install OpenCV's or LCM's arm64 packages beside the amd64 ones (libgdal32 and
# liblcm1 are not Multi-Arch: same), so the C++ shims and the whole binary are not built here.
# Seconds, not part of make test.
ARM64DIR ?= build-arm64
ARM64_DEBS := gcc-aarch64-linux-gnu qemu-user-static libcmocka-dev:arm64 \
	libjpeg62-turbo-dev:arm64 libavcodec-dev:arm64 libavformat-dev:arm64 libswscale-dev:arm64
ARM64_CC := aarch64-linux-gnu-gcc -std=c11 -D_GNU_SOURCE -O2 -Wall -Werror -Iinclude -Isrc \
	-I$(BUILDDIR)/lcmtypes -I/usr/include/libxml2
# test name:the sources it tests (the Hamming distance is header-only)
ARM64_TESTS := hamming: mailbox:src/capture/mailbox.c geom:src/util/geom.c kernels:src/util/kernels.c lk:src/vo/frontend/lk.c

cross-arm64: build
	@dpkg --print-foreign-architectures | grep -qx arm64 || \
		{ $(SUDO) dpkg --add-architecture arm64 && $(SUDO) apt-get update -qq; }
	$(call apt_missing,$(ARM64_DEBS))
	@mkdir -p $(ARM64DIR)
	@for f in $$(find src -name '*.c' | sort); do \
		$(ARM64_CC) -DMVOD_VERSION='"arm64"' -c $$f -o $(ARM64DIR)/$$(echo $$f | tr / _).o \
			|| exit 1; \
	done; echo "cross-arm64: compiled $$(find src -name '*.c' | wc -l) C files of src/ for arm64"
	@for t in $(ARM64_TESTS); do \
		name=$${t%%:*}; srcs=$$(echo $${t#*:} | tr , ' '); \
		$(ARM64_CC) -o $(ARM64DIR)/test_$$name tests/unit/test_$$name.c $$srcs -lcmocka -lpthread \
			-lm || exit 1; \
		qemu-aarch64-static $(ARM64DIR)/test_$$name || exit 1; \
	done
	@file $(ARM64DIR)/test_hamming

# BENCHMARKS.md's tables measured again and checked against the page (bench/run.sh, about 8
# minutes): UPDATE=1 rewrites the tables that disagree, LONG=1 adds the long drives, TABLES="kitti
# calib" measures only those.
bench: build
	bench/run.sh -b $(BUILDDIR) $(if $(filter 1,$(UPDATE)),--update) $(if $(filter 1,$(LONG)),--long) \
		$(TABLES)

# The binaries, LCM types and their bindings for subscribers (libmvod-lcmtypes, headers,
# mvod-lcmtypes.pc, Python), the systemd unit with its sysusers and tmpfiles entries (under
# PREFIX/lib), the example config (PREFIX/share/mvod/mvod.conf.example), and that example as
# /etc/mvod/mvod.conf when there is none yet: an edited config is never overwritten. Meson 1.0
# does not run ldconfig, without which programs do not find the new library.
install: build
	meson configure $(BUILDDIR) --prefix=$(PREFIX)
	meson compile -C $(BUILDDIR)
	DESTDIR=$(DESTDIR) meson install -C $(BUILDDIR) --no-rebuild
	@if [ -z "$(DESTDIR)" ] && ! ldconfig 2>/dev/null; then \
		echo "make install: run ldconfig as root, so programs find libmvod-lcmtypes.so.1"; \
	fi
	@if [ ! -e $(DESTDIR)/etc/mvod/mvod.conf ]; then \
		install -D -m 644 systemd/mvod.conf $(DESTDIR)/etc/mvod/mvod.conf && \
		echo "make install: wrote $(DESTDIR)/etc/mvod/mvod.conf: set [source] and [calibration]"; \
	fi
	@echo "make install: then, as root: systemd-sysusers; systemd-tmpfiles --create;" \
		"systemctl daemon-reload; systemctl enable --now mvod"

clean:
	rm -rf $(BUILDDIR) $(ASANDIR) $(FUZZDIR) $(DEMODIR) $(ARM64DIR)

/*
 * valgrind memcheck on a short run of the real binary, every output on: no memory error and no
 * definitely lost block (tests/valgrind.supp holds LCM's own). Skipped (77) without valgrind,
 * and in sanitizer builds, whose binaries valgrind cannot run.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

/* memcheck's exit status for errors, unlike any mvod gives. */
#define VALGRIND_ERROR 99

static char valgrind[512];

/* valgrind's path from $PATH, or false. */
static bool find_valgrind(void)
{
	const char *path = getenv("PATH");
	for (const char *p = path; p && *p;) {
		size_t len = strcspn(p, ":");
		snprintf(valgrind, sizeof(valgrind), "%.*s/valgrind", (int)len, p);
		if (access(valgrind, X_OK) == 0)
			return true;
		p += len + (p[len] == ':');
	}
	return false;
}

static void test_no_definite_leak(void **state)
{
	(void)state;
	char dir[300], src[400], cal[400], traj[400], url[420], supp[600];
	snprintf(dir, sizeof(dir), "%s/seq", harness_tmpdir());
	/* Ten frames take memcheck about 15 s; each stage runs, tracking included. */
	harness_synth(dir, "forward", 10, "mkv", "--size", "160x120", NULL);
	snprintf(src, sizeof(src), "file:%s/video.mkv", dir);
	snprintf(cal, sizeof(cal), "%s/calib.json", dir);
	snprintf(traj, sizeof(traj), "%s/out.tum", dir);
	snprintf(url, sizeof(url), "file://%s/out.lcmlog?mode=w", dir);
	snprintf(supp, sizeof(supp), "--suppressions=%s", harness_bin("MVOD_VALGRIND_SUPP"));
	char *argv[] = {valgrind, "-q", "--leak-check=full", "--show-leak-kinds=definite",
			"--errors-for-leak-kinds=definite", "--error-exitcode=99", supp,
			(char *)harness_bin("MVOD"), "-q", "--source", src, "--calib", cal,
			"--trajectory", traj, "--lcm-url", url, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("valgrind: status %d%s:\n%s", r.status,
			 r.status == VALGRIND_ERROR ? " (memcheck errors)" : "", r.err);
}

int main(void)
{
#if defined(__SANITIZE_ADDRESS__)
	return EXIT_SKIP;
#endif
	if (!find_valgrind())
		return EXIT_SKIP;
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_no_definite_leak),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}

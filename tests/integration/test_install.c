/*
 * `meson install` into a DESTDIR, and the installed service files checked by systemd's own
 * tools against that root: systemd-sysusers creates the mvod user (in group video),
 * systemd-tmpfiles creates /var/lib/mvod owned by it, and `systemd-analyze verify` finds
 * nothing to say about mvod.service nor about an instance of mvod@.service (their ExecStart
 * binary exists in the root). Exits 77 when
 * systemd-analyze is not installed.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

static char root[300];

/* Runs argv, failing the test with its output unless it exits 0 silently. */
static void run_quiet(const char *what, char *const argv[])
{
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0 || r.err[0] || r.out[0])
		fail_msg("%s: exit %d\n%s%s", what, r.status, r.out, r.err);
}

static void test_install_and_verify(void **state)
{
	(void)state;
	snprintf(root, sizeof(root), "%s/root", harness_tmpdir());
	harness_meson_install(root);
	/*
	 * What the root needs besides mvod for the tools to judge it as a system: the units the
	 * service depends on (sysinit.target, ...), /bin/kill of ExecReload, /etc for users.
	 */
	char cmd[2048];
	snprintf(cmd, sizeof(cmd),
		 "cd %s && mkdir -p lib/systemd bin etc && cp -r /lib/systemd/system lib/systemd/ "
		 "&& cp /bin/kill bin/",
		 root);
	assert_int_equal(system(cmd), 0);
	char rootopt[320];
	snprintf(rootopt, sizeof(rootopt), "--root=%s", root);
	char *sysusers[] = {"/usr/bin/systemd-sysusers", rootopt, NULL};
	struct run_result r;
	assert_int_equal(harness_run(sysusers, &r), 0);
	assert_true(r.exited && r.status == 0);
	char path[400], line[256];
	snprintf(path, sizeof(path), "%s/etc/group", root);
	FILE *f = fopen(path, "r");
	assert_non_null(f);
	int in_video = 0;
	while (fgets(line, sizeof(line), f))
		in_video |= strncmp(line, "video:", 6) == 0 && strstr(line, "mvod");
	fclose(f);
	assert_true(in_video);
	if (geteuid() == 0) { /* chown to the new user needs root */
		char *tmpfiles[] = {"/usr/bin/systemd-tmpfiles", rootopt, "--create", NULL};
		run_quiet("systemd-tmpfiles", tmpfiles);
		struct stat st;
		snprintf(path, sizeof(path), "%s/var/lib/mvod", root);
		assert_int_equal(stat(path, &st), 0);
		assert_true(S_ISDIR(st.st_mode) && st.st_uid != 0);
	}
	char *verify[] = {"/usr/bin/systemd-analyze", "verify", rootopt, "mvod.service", NULL};
	run_quiet("systemd-analyze verify", verify);
	/* The instanced unit, one camera per config: instance front reads /etc/mvod/front.conf. */
	char *verify_at[] = {"/usr/bin/systemd-analyze", "verify", rootopt, "mvod@front.service",
			     NULL};
	run_quiet("systemd-analyze verify mvod@front", verify_at);
	char unit[8192];
	snprintf(cmd, sizeof(cmd), "find %s -name 'mvod@.service' -path '*/lib/systemd/system/*' "
		 "-exec cat {} + > %s/unit.txt", root, harness_tmpdir());
	assert_int_equal(system(cmd), 0);
	snprintf(path, sizeof(path), "%s/unit.txt", harness_tmpdir());
	harness_read_file(path, unit, sizeof(unit));
	assert_non_null(strstr(unit, "mvod run --config /etc/mvod/%i.conf\n"));
	assert_non_null(strstr(unit, "\nRestartPreventExitStatus=2\n"));
	/*
	 * With a JDK and LCM's lcm.jar (liblcm-java) the types' jar for lcm-spy is built and
	 * installed, holding both classes.
	 */
	if (access("/usr/bin/javac", X_OK) == 0 && access("/usr/share/java/lcm.jar", R_OK) == 0) {
		snprintf(cmd, sizeof(cmd), "jar tf \"$(find %s -path '*/share/mvod/java/mvod-lcmtypes.jar')\" "
			 "| grep -c '^mvod/\\(pose\\|status\\)_t.class$' | grep -qx 2", root);
		if (system(cmd) != 0)
			fail_msg("share/mvod/java/mvod-lcmtypes.jar is missing or lacks the classes");
	}
	/* The example config, under whichever prefix the build was set up with. */
	snprintf(cmd, sizeof(cmd), "find %s -path '*/share/mvod/mvod.conf.example' | grep -q .",
		 root);
	assert_int_equal(system(cmd), 0);
}

int main(void)
{
	if (access("/usr/bin/systemd-analyze", X_OK) != 0 ||
	    access("/usr/bin/systemd-sysusers", X_OK) != 0) {
		fprintf(stderr, "systemd-analyze or systemd-sysusers is not installed: skipped\n");
		return EXIT_SKIP;
	}
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_install_and_verify),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}

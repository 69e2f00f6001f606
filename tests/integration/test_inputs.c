/*
 * Every input checked as the best ones are (issue 36), end to end through the real binary:
 * nested YAML refused before libyaml parses it, and a stop honoured while mvod starts; each
 * run is bounded in time, so what once hung fails here instead of holding the suite.
 */
#include <errno.h>
#include <fcntl.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

/* 10 frames of 320x240: enough for every refusal, which comes before the first frame. */
#define FRAMES 10
/*
 * Seconds a refused run may take: start-up is ~1 s; the cases here once took minutes (a
 * nested calibration 210 s) or for ever (a FIFO).
 */
#define BOUND_S 30

static char png[256], euroc[256], calib[300];

static int setup(void **state)
{
	(void)state;
	snprintf(png, sizeof(png), "%s", harness_tmp_path("png"));
	snprintf(euroc, sizeof(euroc), "%s", harness_tmp_path("euroc"));
	harness_synth(png, "forward", FRAMES, "png", "--size", "320x240", NULL);
	harness_synth(euroc, "forward", FRAMES, "euroc", "--size", "320x240", NULL);
	snprintf(calib, sizeof(calib), "%s/calib.json", png);
	return 0;
}

/*
 * Runs argv (NULL-terminated) for at most BOUND_S seconds, stdout and stderr into r; a run
 * that takes longer is killed and fails the test.
 */
static void run_bounded(char *const argv[], struct run_result *r)
{
	char out[300], err[300];
	snprintf(out, sizeof(out), "%s/run.out", harness_tmpdir());
	snprintf(err, sizeof(err), "%s/run.err", harness_tmpdir());
	pid_t pid = harness_spawn(argv, out, err);
	int st = 0, waited = 0;
	while (waitpid(pid, &st, WNOHANG) == 0) {
		if (waited++ == BOUND_S * 20) {
			kill(pid, SIGKILL);
			waitpid(pid, &st, 0);
			fail_msg("%s still running after %d s", argv[0], BOUND_S);
		}
		usleep(50000);
	}
	r->exited = WIFEXITED(st);
	r->status = WIFEXITED(st) ? WEXITSTATUS(st) : WTERMSIG(st);
	harness_read_file(out, r->out, sizeof(r->out));
	harness_read_file(err, r->err, sizeof(r->err));
}

/* mvod with the arguments (NULL-terminated) fails, in time, saying needle. */
static void expect_refused(const char *needle, ...)
{
	char *argv[24] = {(char *)harness_bin("MVOD")};
	int n = 1;
	va_list ap;
	va_start(ap, needle);
	for (char *a; n < 23 && (a = va_arg(ap, char *));)
		argv[n++] = a;
	va_end(ap);
	struct run_result r;
	run_bounded(argv, &r);
	if (!r.exited || r.status == 0 || !strstr(r.err, needle))
		fail_msg("expected a refusal saying \"%s\", got %s %d: %s%s", needle,
			 r.exited ? "exit" : "signal", r.status, r.out, r.err);
}

/* bytes of c after prefix, into path. */
static void write_repeated(const char *path, const char *prefix, char c, size_t bytes)
{
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs(prefix, f);
	for (size_t i = 0; i < bytes; i++)
		fputc(c, f);
	fclose(f);
}

/*
 * Class 3: nested YAML is refused by the guard before libyaml parses it (a 300 KB calibration
 * took 210 s, a 1 MiB sensor.yaml over 13 minutes), with the line.
 */
static void test_nested_yaml(void **state)
{
	(void)state;
	char images[300], deep[300], sensor[300], source[300];
	snprintf(images, sizeof(images), "images:%s/images", png);
	snprintf(deep, sizeof(deep), "%s/deep.yaml", harness_tmpdir());
	write_repeated(deep, "%YAML:1.0\ncamera_matrix: ", '[', 300000);
	expect_refused("deep.yaml: line 2: nested more than 64 levels deep", "--source", images,
		       "--calib", deep, "--no-lcm", NULL);
	snprintf(sensor, sizeof(sensor), "%s/mav0/cam0/sensor.yaml", euroc);
	write_repeated(sensor, "sensor_type: camera\nintrinsics: ", '[', (1 << 20) - 64);
	snprintf(source, sizeof(source), "euroc:%s", euroc);
	expect_refused("sensor.yaml line 2: nested more than 64 levels deep", "--source", source,
		       "--no-lcm", NULL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_nested_yaml),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}

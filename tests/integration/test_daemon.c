/*
 * mvod as a daemon, through the real binary: the config file (a good one runs, flags override
 * it, a bad one is exit 2 naming file:line and key, --print-config round-trips), systemd's
 * notifications over a NOTIFY_SOCKET of our own (READY=1, STATUS=, WATCHDOG=1, STOPPING=1), and
 * signals: SIGHUP reopens the trajectory and the file:// LCM log by name, SIGTERM stops cleanly,
 * a second one at once.
 *
 * The live runs play a clip rendered at 20 fps with ?realtime=1, so they last the clip's 4 s
 * whatever the machine's speed, long enough to signal them mid-run.
 */
#include <errno.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <poll.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod_status_t.h"

#define FRAMES 80
#define FPS "20"

static char dir[256], video[320], live[340], calib[300];

static int setup(void **state)
{
	(void)state;
	snprintf(dir, sizeof(dir), "%s/seq", harness_tmpdir());
	harness_synth(dir, "forward", FRAMES, "mkv", "--fps", FPS, NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(live, sizeof(live), "%s?realtime=1", video);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	return 0;
}

static const char *tmp_path(char *buf, size_t len, const char *name)
{
	snprintf(buf, len, "%s/%s", harness_tmpdir(), name);
	unlink(buf);
	return buf;
}

/* A config naming the clip, its calibration and a trajectory; extra lines appended. */
static void good_config(const char *path, const char *traj, const char *extra)
{
	char text[2048];
	snprintf(text, sizeof(text),
		 "# written by test_daemon\n[source]\nuri = %s\nmax-frames = 10\n"
		 "[calibration]\nfile = %s\n[lcm]\nenabled = false\n[output]\ntrajectory = %s\n%s",
		 video, calib, traj, extra);
	harness_write_file(path, text);
}

static void test_config_file_runs(void **state)
{
	(void)state;
	char conf[300], traj[300];
	tmp_path(conf, sizeof(conf), "good.conf");
	tmp_path(traj, sizeof(traj), "good.tum");
	good_config(conf, traj, "[log]\nquiet = true\n");
	char *argv[] = {(char *)harness_bin("MVOD"), "--config", conf, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mvod --config failed (%d): %s", r.status, r.err);
	assert_int_equal(harness_traj_lines(traj), 10);
	assert_string_equal(r.out, ""); /* quiet = true: no summary */
	/* A flag beats the file. */
	char *argv2[] = {(char *)harness_bin("MVOD"), "--config", conf, "--max-frames", "4", NULL};
	assert_int_equal(harness_run(argv2, &r), 0);
	assert_true(r.exited && r.status == 0);
	assert_int_equal(harness_traj_lines(traj), 4);
}

/* Exit 2, the message on stderr, and the trajectory the file names never created. */
static void expect_config_error(const char *text, const char *needle)
{
	char conf[300], traj[300], full[1024];
	tmp_path(conf, sizeof(conf), "bad.conf");
	tmp_path(traj, sizeof(traj), "bad.tum");
	snprintf(full, sizeof(full), "[output]\ntrajectory = %s\n%s", traj, text);
	harness_write_file(conf, full);
	char *argv[] = {(char *)harness_bin("MVOD"), "--config", conf, "--source", video,
			"--calib", calib, "--no-lcm", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	char want[512];
	snprintf(want, sizeof(want), "%s:%s", conf, needle);
	if (!r.exited || r.status != 2 || !strstr(r.err, want))
		fail_msg("expected exit 2 and \"%s\", got %d: %s", want, r.status, r.err);
	assert_int_equal(access(traj, F_OK), -1);
}

static void test_bad_config_exits_2(void **state)
{
	(void)state;
	expect_config_error("[vo]\nratio = 2\n", "4: [vo] ratio = 2: expected a number in [0.1, 1]");
	expect_config_error("[vo]\nratio = 0.8\nfeature = 10\n", "5: [vo] feature: unknown key");
	expect_config_error("\n[camera]\ndevice = x\n", "5: [camera] device: unknown section");
	expect_config_error("[lcm]\nenabled = sometimes\n", "4: [lcm] enabled = sometimes");
	expect_config_error("[vo]\nratio 0.8\n", "4: not a [section] or key = value line");
	/* An explicitly named file that is not there is an error, not the defaults. */
	char *argv[] = {(char *)harness_bin("MVOD"), "--config", "/nonexistent/mvod.conf",
			"--source", video, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_true(r.exited);
	assert_int_equal(r.status, 2);
	assert_non_null(strstr(r.err, "cannot read /nonexistent/mvod.conf"));
}

static void test_print_config_round_trip(void **state)
{
	(void)state;
	char conf[300], traj[300], printed[300];
	tmp_path(conf, sizeof(conf), "print.conf");
	tmp_path(printed, sizeof(printed), "printed.conf");
	good_config(conf, tmp_path(traj, sizeof(traj), "print.kitti"), "[vo]\nratio = 0.7\n");
	char *argv[] = {(char *)harness_bin("MVOD"), "--config", conf, "--ratio", "0.5",
			"--status-rate", "2.5", "--print-config", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_true(r.exited && r.status == 0);
	/*
	 * The flag over the file, the file over the defaults, the format from the .kitti name,
	 * printed as a comment: it follows the name, not pinned to it (issue 18).
	 */
	assert_non_null(strstr(r.out, "\nratio = 0.5\n"));
	assert_non_null(strstr(r.out, "\nstatus-rate = 2.5\n"));
	assert_non_null(strstr(r.out, "\nmax-frames = 10\n"));
	assert_non_null(strstr(r.out, "\n# format = kitti  (not set"));
	assert_non_null(strstr(r.out, "\nenabled = false\n"));
	harness_write_file(printed, r.out);
	char first[sizeof(r.out)];
	strcpy(first, r.out);
	char *argv2[] = {(char *)harness_bin("MVOD"), "--config", printed, "--print-config", NULL};
	assert_int_equal(harness_run(argv2, &r), 0);
	assert_true(r.exited && r.status == 0);
	assert_string_equal(r.out, first);
	/* Nothing ran: printing is all --print-config does. */
	assert_int_equal(access(traj, F_OK), -1);
}

/* Messages received on a notify socket while the child runs, joined by '|'. */
static void collect_notifications(int sock, pid_t pid, char *out, size_t len, int *status,
				  int *exited)
{
	size_t used = 0;
	out[0] = '\0';
	for (bool done = false;;) {
		/* Drain while mvod runs: a full datagram queue would block its sd_notify. */
		struct pollfd p = {.fd = sock, .events = POLLIN};
		if (poll(&p, 1, done ? 0 : 20) > 0) {
			char msg[512];
			ssize_t n = recv(sock, msg, sizeof(msg) - 1, 0);
			assert_true(n >= 0);
			msg[n] = '\0';
			int w = snprintf(out + used, len - used, "%s|", msg);
			used += w > 0 && (size_t)w < len - used ? (size_t)w : 0;
			continue;
		}
		if (done)
			return;
		int st;
		if (waitpid(pid, &st, WNOHANG) == pid) {
			*exited = WIFEXITED(st);
			*status = WIFEXITED(st) ? WEXITSTATUS(st) : WTERMSIG(st);
			done = true;
		}
	}
}

/*
 * Runs mvod (with argv) under a NOTIFY_SOCKET, WATCHDOG_USEC and watchdog_pid if not NULL;
 * returns its exit status.
 */
static int run_notified_status(char *const argv[], const char *watchdog_pid, char *out,
			       size_t len)
{
	char path[300];
	tmp_path(path, sizeof(path), "notify.sock");
	int sock = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
	assert_true(sock >= 0);
	struct sockaddr_un sa = {.sun_family = AF_UNIX};
	assert_true(strlen(path) < sizeof(sa.sun_path));
	memcpy(sa.sun_path, path, strlen(path) + 1);
	assert_int_equal(bind(sock, (struct sockaddr *)&sa, sizeof(sa)), 0);
	setenv("NOTIFY_SOCKET", path, 1);
	setenv("WATCHDOG_USEC", "500000", 1);
	if (watchdog_pid)
		setenv("WATCHDOG_PID", watchdog_pid, 1);
	pid_t pid = harness_spawn(argv, NULL, NULL);
	unsetenv("NOTIFY_SOCKET");
	unsetenv("WATCHDOG_USEC");
	unsetenv("WATCHDOG_PID");
	int status = -1, exited = 0;
	collect_notifications(sock, pid, out, len, &status, &exited);
	close(sock);
	if (!exited)
		fail_msg("mvod killed by signal %d: notifications %s", status, out);
	return status;
}

/* The same, for a run that must succeed. */
static void run_notified(char *const argv[], const char *watchdog_pid, char *out, size_t len)
{
	int status = run_notified_status(argv, watchdog_pid, out, len);
	if (status != 0)
		fail_msg("mvod failed (%d): notifications %s", status, out);
}

/*
 * The start path of the service with the example config's calibration missing (issue 18):
 * exit status 2, a configuration error, which mvod.service lists in RestartPreventExitStatus=
 * (no restart loop), and a STATUS= line that says why, for `systemctl status`. Never READY=1.
 */
static void test_missing_calibration_stops_service(void **state)
{
	(void)state;
	static char got[4096];
	char conf[300], unit[8192];
	tmp_path(conf, sizeof(conf), "nocalib.conf");
	char text[1024];
	snprintf(text, sizeof(text), "[source]\nuri = %s\n[calibration]\nfile = %s/none.json\n"
		 "[lcm]\nenabled = false\n", video, dir);
	harness_write_file(conf, text);
	char *argv[] = {(char *)harness_bin("MVOD"), "run", "--config", conf, NULL};
	assert_int_equal(run_notified_status(argv, NULL, got, sizeof(got)), 2);
	if (!strstr(got, "STATUS=stopped: the calibration ") || !strstr(got, "/none.json"))
		fail_msg("no STATUS= naming the calibration: %s", got);
	assert_null(strstr(got, "READY=1"));
	/* The unit does not restart on 2. */
	const char *src = getenv("MVOD_SRCDIR");
	assert_non_null(src);
	char path[512];
	snprintf(path, sizeof(path), "%s/systemd/mvod.service.in", src);
	harness_read_file(path, unit, sizeof(unit));
	assert_non_null(strstr(unit, "\nRestartPreventExitStatus=2\n"));
}

static void test_sd_notify(void **state)
{
	(void)state;
	static char got[65536];
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", live, "--calib", calib,
			"--no-lcm", "-q", NULL};
	/*
	 * WATCHDOG_PID unset: the watchdog is ours (sd_watchdog_enabled). Over the clip's 4 s a
	 * keep-alive goes out every third of the 0.5 s period, so some follow READY=1.
	 */
	run_notified(argv, NULL, got, sizeof(got));
	const char *ready = strstr(got, "READY=1|");
	const char *stopping = strstr(got, "STOPPING=1|");
	if (!ready || !stopping)
		fail_msg("READY=1 or STOPPING=1 missing: %s", got);
	const char *status = strstr(ready, "STATUS=");
	const char *dog = strstr(ready, "WATCHDOG=1|");
	if (!status || !dog || status > stopping || dog > stopping)
		fail_msg("expected READY=1, then STATUS= and WATCHDOG=1, then STOPPING=1: %s", got);
	/* Once each, and STOPPING=1 the very last. */
	assert_null(strstr(ready + 1, "READY=1"));
	assert_string_equal(stopping, "STOPPING=1|");
	assert_non_null(strstr(got, " fps, "));
	/* The last status line says so. */
	assert_non_null(strstr(got, "STATUS=STOPPING"));

	/* A WATCHDOG_PID that is not mvod's: the watchdog belongs to someone else. */
	char *argv2[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib,
			 "--no-lcm", "-q", "--max-frames", "15", NULL};
	run_notified(argv2, "1", got, sizeof(got));
	assert_non_null(strstr(got, "READY=1|"));
	assert_non_null(strstr(got, "STOPPING=1|"));
	assert_null(strstr(got, "WATCHDOG=1"));
}

/* mvod on the realtime clip in the background, with a trajectory, an LCM log, maybe a plot. */
static pid_t start_live(const char *traj, const char *log, const char *out, const char *plot)
{
	char url[400];
	snprintf(url, sizeof(url), "file://%s?mode=w", log);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", live, "--calib", calib,
			"--trajectory", (char *)traj, "--lcm-url", url, "--plot", (char *)plot, NULL};
	if (!plot)
		argv[9] = NULL;
	return harness_spawn(argv, out, NULL);
}

/* Frames processed, from the summary line "mvod: N frames in ...". */
static int summary_frames(const char *out)
{
	FILE *f = fopen(out, "r");
	assert_non_null(f);
	int n = -1;
	assert_int_equal(fscanf(f, "mvod: %d frames", &n), 1);
	fclose(f);
	return n;
}

/* The poses of a log, at least 3, each frame after the one before. */
static int log_poses(const char *log, mvod_pose_t *p, int max)
{
	int n = harness_poses(log, p, max);
	assert_true(n >= 3 && n < max);
	for (int i = 1; i < n; i++)
		assert_true(p[i].frame > p[i - 1].frame);
	return n;
}

static void test_sighup_reopens_trajectory(void **state)
{
	(void)state;
	char traj[300], rotated[300], log[300], log_rotated[300], out[300];
	tmp_path(traj, sizeof(traj), "hup.tum");
	tmp_path(rotated, sizeof(rotated), "hup.tum.1");
	tmp_path(log_rotated, sizeof(log_rotated), "hup.lcmlog.1");
	pid_t pid = start_live(traj, tmp_path(log, sizeof(log), "hup.lcmlog"),
			       tmp_path(out, sizeof(out), "hup.out"), NULL);
	harness_wait_lines(traj, 3, pid);
	/* What logrotate does: rename, then SIGHUP. */
	assert_int_equal(rename(traj, rotated), 0);
	assert_int_equal(rename(log, log_rotated), 0);
	kill(pid, SIGHUP);
	harness_wait_lines(traj, 3, pid);
	kill(pid, SIGTERM);
	int st;
	assert_true(harness_wait(pid, &st));
	assert_int_equal(st, 0);
	/* Both files hold whole lines only, together every frame, the new one after the old. */
	struct mvod_traj a, b;
	char err[512];
	if (mvod_traj_load(rotated, &a, err, sizeof(err)) || mvod_traj_load(traj, &b, err, sizeof(err)))
		fail_msg("%s", err);
	assert_int_equal(a.n, harness_count_lines(rotated));
	assert_int_equal(b.n, harness_count_lines(traj));
	assert_true(a.n >= 3 && b.n >= 3);
	assert_int_equal(a.n + b.n, summary_frames(out));
	assert_true(b.t[0] > a.t[a.n - 1]);
	mvod_traj_free(&a);
	mvod_traj_free(&b);
	/* The LCM log the same way: every frame's pose in one of the two, the new after the old. */
	static mvod_pose_t pa[2 * FRAMES], pb[2 * FRAMES];
	int na = log_poses(log_rotated, pa, 2 * FRAMES), nb = log_poses(log, pb, 2 * FRAMES);
	assert_int_equal(na + nb, summary_frames(out));
	assert_true(pb[0].frame > pa[na - 1].frame);
}

static void test_sigterm_stops_cleanly(void **state)
{
	(void)state;
	char traj[300], log[300], out[300];
	tmp_path(traj, sizeof(traj), "term.tum");
	pid_t pid = start_live(traj, tmp_path(log, sizeof(log), "term.lcmlog"),
			       tmp_path(out, sizeof(out), "term.out"), NULL);
	harness_wait_lines(traj, 3, pid);
	kill(pid, SIGTERM);
	int st;
	assert_true(harness_wait(pid, &st));
	assert_int_equal(st, 0);
	mvod_status_t all[256];
	int n = harness_statuses(log, all, 256);
	assert_true(n >= 2 && n <= 256);
	/* The last status is STATE_STOPPING, with the totals: one pose line per frame. */
	assert_int_equal(all[n - 1].state, 5);
	assert_int_equal(harness_traj_lines(traj), all[n - 1].frames);
	assert_int_equal(summary_frames(out), all[n - 1].frames);
}

static void test_second_sigterm_exits_at_once(void **state)
{
	(void)state;
	char traj[300], log[300], out[300], plot[300];
	tmp_path(traj, sizeof(traj), "twice.tum");
	/* The plot only lengthens the clean shutdown that the second signal cuts short. */
	pid_t pid = start_live(traj, tmp_path(log, sizeof(log), "twice.lcmlog"),
			       tmp_path(out, sizeof(out), "twice.out"),
			       tmp_path(plot, sizeof(plot), "twice.png"));
	harness_wait_lines(traj, 3, pid);
	/*
	 * Two different signals, so that the second is not merged into the first while pending;
	 * both are sent before mvod's clean shutdown (capture thread, plot, fsync) can finish.
	 */
	kill(pid, SIGTERM);
	kill(pid, SIGINT);
	int st;
	assert_true(harness_wait(pid, &st));
	/* The second signal's _exit(128 + signal), whichever arrived second; not the clean 0. */
	if (st != 128 + SIGINT && st != 128 + SIGTERM)
		fail_msg("exit status %d: not the immediate exit of a second signal", st);
	assert_true(harness_traj_lines(traj) >= 3);
}

/*
 * --status-rate 10: periodic status at most ten times a second, by the uptimes the statuses
 * themselves carry. How many statuses a run holds depends on how fast the machine processes
 * the clip, so no count is asserted: timing belongs in benchmarks, not tests.
 */
static void test_status_rate(void **state)
{
	(void)state;
	char log[300], url[400];
	tmp_path(log, sizeof(log), "rate.lcmlog");
	snprintf(url, sizeof(url), "file://%s?mode=w", log);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", live, "--calib", calib,
			"--lcm-url", url, "--status-rate", "10", "-q", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_true(r.exited && r.status == 0);
	mvod_status_t all[256];
	int n = harness_statuses(log, all, 256);
	assert_true(n >= 2 && n <= 256);
	/* At most one status per frame, but for the closing one. */
	assert_true(n <= all[n - 1].frames + 1);
	/* Never closer than 0.1 s, except for a state change or the final status. */
	for (int i = 1; i + 1 < n; i++)
		if (all[i].state == all[i - 1].state)
			assert_true(all[i].uptime_s - all[i - 1].uptime_s >= 0.1 - 1e-9);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_config_file_runs),
		cmocka_unit_test(test_bad_config_exits_2),
		cmocka_unit_test(test_print_config_round_trip),
		cmocka_unit_test(test_missing_calibration_stops_service),
		cmocka_unit_test(test_sd_notify),
		cmocka_unit_test(test_sighup_reopens_trajectory),
		cmocka_unit_test(test_sigterm_stops_cleanly),
		cmocka_unit_test(test_second_sigterm_exits_at_once),
		cmocka_unit_test(test_status_rate),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}

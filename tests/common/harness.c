#include "harness.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>
#include <lcm/eventlog.h>

#include "mvod/capture.h"
#include "mvod/ipc.h"
#include "mvod_status_t.h"
#include "mvod_pose_t.h"

static char tmpdir[64];

/*
 * MVOD_TEST_FILTER=PATTERN (cmocka's * and ? wildcards) runs only the matching test cases of
 * every test binary, before main: how make mutate runs one case of a long integration test.
 */
__attribute__((constructor)) static void filter_from_env(void)
{
	const char *pattern = getenv("MVOD_TEST_FILTER");
	if (pattern && *pattern)
		cmocka_set_test_filter(pattern);
}

const char *harness_bin(const char *env)
{
	const char *p = getenv(env);
	if (!p)
		fail_msg("%s is not set: run the tests through meson test", env);
	return p;
}

const char *harness_tmpdir(void)
{
	if (!tmpdir[0]) {
		strcpy(tmpdir, "/tmp/mvod-itest-XXXXXX");
		if (!mkdtemp(tmpdir))
			fail_msg("mkdtemp: %s", strerror(errno));
	}
	return tmpdir;
}

const char *harness_tmp_path(const char *name)
{
	static char path[8][512];
	static int k;
	char *p = path[k++ % 8];
	snprintf(p, sizeof(path[0]), "%s/%s", harness_tmpdir(), name);
	return p;
}

void harness_cleanup(void)
{
	if (!tmpdir[0])
		return;
	char cmd[128];
	snprintf(cmd, sizeof(cmd), "rm -rf '%s'", tmpdir);
	if (system(cmd) != 0)
		fprintf(stderr, "could not remove %s\n", tmpdir);
	tmpdir[0] = '\0';
}

int harness_teardown(void **state)
{
	(void)state;
	harness_cleanup();
	return 0;
}

/* Drains both pipes until the child closes them, so neither can fill up and block it. */
static void drain(int fo, int fe, struct run_result *r)
{
	size_t no = 0, ne = 0;
	struct pollfd p[2] = {{.fd = fo, .events = POLLIN}, {.fd = fe, .events = POLLIN}};
	int open_fds = 2;
	while (open_fds) {
		if (poll(p, 2, -1) < 0 && errno != EINTR)
			break;
		for (int i = 0; i < 2; i++) {
			if (p[i].fd < 0 || !(p[i].revents & (POLLIN | POLLHUP)))
				continue;
			char *buf = i ? r->err : r->out;
			size_t *n = i ? &ne : &no;
			char sink[4096];
			size_t room = sizeof(r->out) - 1 - *n;
			ssize_t k = read(p[i].fd, room ? buf + *n : sink, room ? room : sizeof(sink));
			if (k <= 0) {
				close(p[i].fd);
				p[i].fd = -1;
				open_fds--;
			} else if (room) {
				*n += (size_t)k;
			}
		}
	}
	r->out[no] = '\0';
	r->err[ne] = '\0';
}

int harness_run(char *const argv[], struct run_result *r)
{
	int po[2], pe[2];
	memset(r, 0, sizeof(*r));
	if (pipe(po) || pipe(pe))
		return -errno;
	pid_t pid = fork();
	if (pid < 0)
		return -errno;
	if (pid == 0) {
		dup2(po[1], 1);
		dup2(pe[1], 2);
		close(po[0]);
		close(pe[0]);
		execv(argv[0], argv);
		_exit(127);
	}
	close(po[1]);
	close(pe[1]);
	drain(po[0], pe[0], r);
	int st;
	while (waitpid(pid, &st, 0) < 0)
		if (errno != EINTR)
			return -errno;
	r->exited = WIFEXITED(st);
	r->status = r->exited ? WEXITSTATUS(st) : WTERMSIG(st);
	return 0;
}

/* A child running argv with stdout on the descriptor out and stderr into err_path. */
static pid_t spawn(char *const argv[], int out, const char *err_path)
{
	pid_t pid = fork();
	assert_true(pid >= 0);
	if (pid == 0) {
		int err = open(err_path ? err_path : "/dev/null", O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(out, 1);
		dup2(err, 2);
		execv(argv[0], argv);
		_exit(127);
	}
	return pid;
}

pid_t harness_spawn(char *const argv[], const char *out_path, const char *err_path)
{
	int out = open(out_path ? out_path : "/dev/null", O_WRONLY | O_CREAT | O_TRUNC, 0644);
	assert_true(out >= 0);
	pid_t pid = spawn(argv, out, err_path);
	close(out);
	return pid;
}

int harness_run_reader_gone(char *const argv[], const char *err_path, int *status)
{
	int fds[2];
	assert_int_equal(pipe(fds), 0);
	close(fds[0]);
	pid_t pid = spawn(argv, fds[1], err_path);
	close(fds[1]);
	return harness_wait(pid, status);
}

/* Whether pid has path open (the same device and inode among its descriptors). */
static bool holds_open(pid_t pid, const char *path)
{
	struct stat want, st;
	char dir[64], fd_path[600];
	assert_int_equal(stat(path, &want), 0);
	snprintf(dir, sizeof(dir), "/proc/%d/fd", (int)pid);
	DIR *d = opendir(dir);
	bool found = false;
	for (struct dirent *e = d ? readdir(d) : NULL; e && !found; e = readdir(d)) {
		snprintf(fd_path, sizeof(fd_path), "%s/%s", dir, e->d_name);
		found = stat(fd_path, &st) == 0 && st.st_dev == want.st_dev && st.st_ino == want.st_ino;
	}
	if (d)
		closedir(d);
	return found;
}

void harness_wait_open(pid_t pid, const char *path)
{
	char exe[64], self[PATH_MAX] = "", want[PATH_MAX];
	snprintf(exe, sizeof(exe), "/proc/%d/exe", (int)pid);
	assert_non_null(realpath(harness_bin("MVOD"), want));
	int st;
	for (ssize_t n = 0; n <= 0 || strcmp(self, want) != 0 || !holds_open(pid, path);) {
		n = readlink(exe, self, sizeof(self) - 1);
		self[n > 0 ? n : 0] = '\0';
		if (waitpid(pid, &st, WNOHANG) == pid)
			fail_msg("mvod ended (%d) before it opened %s", st, path);
		usleep(1000);
	}
}

int harness_wait(pid_t pid, int *status)
{
	int st;
	while (waitpid(pid, &st, 0) < 0)
		if (errno != EINTR)
			fail_msg("waitpid: %s", strerror(errno));
	*status = WIFEXITED(st) ? WEXITSTATUS(st) : WTERMSIG(st);
	return WIFEXITED(st);
}

void harness_source_open_fails(const char *uri, int code, const char *needle)
{
	struct mvod_source *src = NULL;
	char err[512] = "";
	assert_int_equal(mvod_source_open(uri, &src, err, sizeof(err)), code);
	assert_null(src);
	if (!strstr(err, needle))
		fail_msg("\"%s\" does not say \"%s\"", err, needle);
}

void harness_write_file(const char *path, const char *text)
{
	FILE *f = fopen(path, "w");
	if (!f)
		fail_msg("cannot write %s: %s", path, strerror(errno));
	fputs(text, f);
	assert_int_equal(fclose(f), 0);
}

void harness_read_file(const char *path, char *buf, size_t len)
{
	buf[0] = '\0';
	FILE *f = fopen(path, "r");
	if (!f)
		return;
	size_t n = fread(buf, 1, len - 1, f);
	buf[n] = '\0';
	fclose(f);
}

char *harness_slurp(const char *dir, const char *name, size_t *len)
{
	char path[512];
	snprintf(path, sizeof(path), "%s/%s", dir, name);
	FILE *f = fopen(path, "rb");
	if (!f)
		fail_msg("%s is missing", path);
	fseek(f, 0, SEEK_END);
	long n = ftell(f);
	fseek(f, 0, SEEK_SET);
	char *buf = malloc((size_t)n + 1);
	assert_non_null(buf);
	assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
	buf[n] = '\0';
	fclose(f);
	*len = (size_t)n;
	return buf;
}

int harness_traj_lines(const char *path)
{
	struct mvod_traj t;
	char err[512];
	if (mvod_traj_load(path, &t, err, sizeof(err)))
		fail_msg("%s", err);
	int n = t.n;
	mvod_traj_free(&t);
	assert_int_equal(harness_count_lines(path), n);
	return n;
}

int harness_count_lines(const char *path)
{
	FILE *f = fopen(path, "r");
	if (!f)
		return -1;
	int n = 0, c;
	while ((c = fgetc(f)) != EOF)
		n += c == '\n';
	fclose(f);
	return n;
}

void harness_wait_lines(const char *path, int n, pid_t pid)
{
	int st;
	while (harness_count_lines(path) < n) {
		if (waitpid(pid, &st, WNOHANG) == pid)
			fail_msg("the process ended (status %d) before %s had %d lines", st, path, n);
		usleep(1000);
	}
}

int harness_signal_after(char *const argv[], const char *path, int lines, int sig)
{
	pid_t pid = harness_spawn(argv, NULL, NULL);
	harness_wait_lines(path, lines, pid);
	kill(pid, sig);
	int st;
	while (waitpid(pid, &st, 0) < 0)
		if (errno != EINTR)
			fail_msg("waitpid: %s", strerror(errno));
	return st;
}

void harness_synth(const char *dir, const char *path_name, int frames, const char *format, ...)
{
	char nframes[16];
	snprintf(nframes, sizeof(nframes), "%d", frames);
	char *argv[32] = {(char *)harness_bin("MVOD_SYNTH"), "--out", (char *)dir, "--path",
			  (char *)path_name, "--frames", nframes, "--format", (char *)format};
	int n = 9;
	va_list ap;
	va_start(ap, format);
	for (char *a; n < 31 && (a = va_arg(ap, char *));)
		argv[n++] = a;
	va_end(ap);
	argv[n] = NULL;
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod-synth %s failed (%d): %s", path_name, r.status, r.err);
}

void harness_compare(const char *est_path, const char *gt_path, int sim3, struct traj_errors *e)
{
	struct mvod_traj est, gt;
	char err[512];
	memset(e, 0, sizeof(*e));
	if (mvod_traj_load(est_path, &est, err, sizeof(err)))
		fail_msg("%s", err);
	if (mvod_traj_load(gt_path, &gt, err, sizeof(err)))
		fail_msg("%s", err);
	assert_int_equal(est.n, gt.n);
	e->n = est.n;
	double *pe = calloc((size_t)est.n * 3, sizeof(double));
	double *pg = calloc((size_t)est.n * 3, sizeof(double));
	assert_non_null(pe);
	assert_non_null(pg);
	for (int i = 0; i < est.n; i++) {
		memcpy(pe + 3 * i, est.pose[i].t, sizeof(est.pose[i].t));
		memcpy(pg + 3 * i, gt.pose[i].t, sizeof(gt.pose[i].t));
		double tn = mvod_vec3_norm(est.pose[i].t);
		if (tn > e->max_translation)
			e->max_translation = tn;
		if (i > 0) {
			mvod_rpe_add(&e->rpe, &est.pose[i - 1], &est.pose[i], &gt.pose[i - 1], &gt.pose[i]);
			e->length_m += mvod_vec3_dist(gt.pose[i].t, gt.pose[i - 1].t);
		}
	}
	mvod_rpe_finish(&e->rpe);
	double R[9], t[3];
	/*
	 * No alignment exists for an estimate that never moved: its error is unbounded, so that
	 * every `ate_m < bound` fails, as it must when the camera did move.
	 */
	if (mvod_umeyama(pe, pg, est.n, sim3, R, t, &e->scale) == 0)
		e->ate_m = mvod_ate_rmse(pe, pg, est.n, R, t, e->scale);
	else
		e->ate_m = INFINITY;
	if (mvod_scale_drift(pe, pg, est.n, &e->scale_drift) != 0)
		e->scale_drift = NAN;
	free(pe);
	free(pg);
	mvod_traj_free(&est);
	mvod_traj_free(&gt);
}

/* What the one log reader does with each message besides counting it; any may be NULL. */
struct log_sink {
	void (*on_pose)(const mvod_pose_t *msg, void *ctx);
	void (*on_status)(const mvod_status_t *msg, void *ctx);
	void (*on_pose2)(const mvod_pose2_t *msg, void *ctx);
	void (*on_status2)(const mvod_status2_t *msg, void *ctx);
	void *ctx;
};

/* The v2 messages, on the v1 channels' names + "2"; counted apart, and decoded alike. */
static void read_event2(const lcm_eventlog_event_t *e, struct log_contents *c,
			const struct log_sink *s)
{
	if (strcmp(e->channel, MVOD_DEFAULT_POSE_CHANNEL "2") == 0) {
		mvod_pose2_t p;
		bool ok = mvod_pose2_t_decode(e->data, 0, e->datalen, &p) > 0;
		c->bad += !ok;
		if (ok && s->on_pose2)
			s->on_pose2(&p, s->ctx);
		c->poses2++;
	} else if (strcmp(e->channel, MVOD_DEFAULT_STATUS_CHANNEL "2") == 0) {
		mvod_status2_t st;
		bool ok = mvod_status2_t_decode(e->data, 0, e->datalen, &st) > 0;
		c->bad += !ok;
		if (ok && s->on_status2)
			s->on_status2(&st, s->ctx);
		c->statuses2++;
	}
}

static void read_event(const lcm_eventlog_event_t *e, struct log_contents *c,
		       const struct log_sink *s)
{
	if (strcmp(e->channel, MVOD_DEFAULT_POSE_CHANNEL) == 0) {
		mvod_pose_t p;
		bool ok = mvod_pose_t_decode(e->data, 0, e->datalen, &p) > 0;
		c->bad += !ok;
		c->gaps += ok && p.frame != c->last_frame + 1;
		c->last_frame = ok ? p.frame : c->last_frame;
		if (ok && s->on_pose)
			s->on_pose(&p, s->ctx);
		c->poses++;
	} else if (strcmp(e->channel, MVOD_DEFAULT_STATUS_CHANNEL) == 0) {
		bool ok = mvod_status_t_decode(e->data, 0, e->datalen, &c->last_status) > 0;
		c->bad += !ok;
		if (ok && s->on_status)
			s->on_status(&c->last_status, s->ctx);
		c->statuses++;
	} else {
		read_event2(e, c, s);
	}
}

static void read_log(const char *path, struct log_contents *c, const struct log_sink *s)
{
	memset(c, 0, sizeof(*c));
	c->last_frame = -1;
	lcm_eventlog_t *ev = lcm_eventlog_create(path, "r");
	if (!ev)
		fail_msg("cannot read the LCM log %s", path);
	lcm_eventlog_event_t *e;
	while ((e = lcm_eventlog_read_next_event(ev))) {
		read_event(e, c, s);
		lcm_eventlog_free_event(e);
	}
	lcm_eventlog_destroy(ev);
}

void harness_read_log(const char *path, struct log_contents *c,
		      void (*on_status)(const mvod_status_t *msg, void *ctx), void *ctx)
{
	read_log(path, c, &(struct log_sink){.on_status = on_status, .ctx = ctx});
}

/* The first max messages of one type (size bytes each), and how many there were. */
struct msg_list {
	void *out;
	size_t size;
	int max, n;
};

static void keep(struct msg_list *l, const void *msg)
{
	if (l->n < l->max)
		memcpy((char *)l->out + (size_t)l->n * l->size, msg, l->size);
	l->n++;
}

static void keep_pose(const mvod_pose_t *msg, void *ctx)
{
	keep(ctx, msg);
}

static void keep_status(const mvod_status_t *msg, void *ctx)
{
	keep(ctx, msg);
}

static void keep_pose2(const mvod_pose2_t *msg, void *ctx)
{
	keep(ctx, msg);
}

static void keep_status2(const mvod_status2_t *msg, void *ctx)
{
	keep(ctx, msg);
}

/* kind: 0 pose_t, 1 status_t, 2 pose2_t, 3 status2_t. */
static int list_messages(const char *log, int kind, void *out, size_t size, int max)
{
	struct msg_list l = {out, size, max, 0};
	struct log_sink s = {kind == 0 ? keep_pose : NULL, kind == 1 ? keep_status : NULL,
			     kind == 2 ? keep_pose2 : NULL, kind == 3 ? keep_status2 : NULL, &l};
	struct log_contents c;
	read_log(log, &c, &s);
	if (c.bad)
		fail_msg("%s: %d messages do not decode", log, c.bad);
	return l.n;
}

int harness_poses(const char *log, mvod_pose_t *out, int max)
{
	return list_messages(log, 0, out, sizeof(*out), max);
}

int harness_statuses(const char *log, mvod_status_t *out, int max)
{
	return list_messages(log, 1, out, sizeof(*out), max);
}

int harness_poses2(const char *log, mvod_pose2_t *out, int max)
{
	return list_messages(log, 2, out, sizeof(*out), max);
}

int harness_statuses2(const char *log, mvod_status2_t *out, int max)
{
	return list_messages(log, 3, out, sizeof(*out), max);
}

void harness_blacken(const char *images, int i, int w, int h)
{
	char path[400];
	snprintf(path, sizeof(path), "%s/%06d.png", images, i);
	assert_int_equal(unlink(path), 0);
	snprintf(path, sizeof(path), "%s/%06d.pgm", images, i);
	FILE *f = fopen(path, "wb");
	assert_non_null(f);
	fprintf(f, "P5\n%d %d\n255\n", w, h);
	for (int k = 0; k < w * h; k++)
		fputc(0, f);
	assert_int_equal(fclose(f), 0);
}

void harness_meson_install(const char *root)
{
	char *install[] = {(char *)harness_bin("MESON"), "install", "-C",
			   (char *)harness_bin("MVOD_BUILDDIR"), "--destdir", (char *)root,
			   "--no-rebuild", "--quiet", NULL};
	struct run_result r;
	assert_int_equal(harness_run(install, &r), 0);
	if (!r.exited || r.status)
		fail_msg("meson install: %s%s", r.out, r.err);
}

/*
 * The output policy on the real binary: mvod never destroys data. An output that is one of the
 * run's inputs is refused and the input left byte for byte; a failed start leaves the
 * trajectory and the LCM log of the run before as they were; a second mvod on the same
 * trajectory or log is refused while the first writes on; a symlink stays a symlink, a
 * character device a device, a FIFO a FIFO (written into, and refused at once when nobody is at
 * its other end); an LCM log that cannot be written is FAULT_PUBLISH and exit 1, and ends on
 * whole events; a second SIGTERM at a random moment (fixed seed) leaves whole lines and whole
 * events; SIGHUP at start-up does not kill; Ctrl-C during calibrate on a file writes nothing.
 * Device nodes are made with mknod in the test's own folder, never the system's.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

/* Paths here are a short temporary folder plus a name: none comes near its buffer. */
#pragma GCC diagnostic ignored "-Wformat-truncation"

#include "harness.h"
#include "mvod/ipc.h"
#include "mvod/pipeline.h"
#include "mvod_status_t.h"

#define FRAMES 20
#define BOARD "charuco:5x7:0.04:0.02:DICT_6X6_250"
#define BOARD_VIEWS 40

static char seq[256], images[512], video[512], calib[512], gt[512], times[512], frame[512];
static char mkv[512], cfg[512], traj[512], lcmlog[512], url[600];

static int setup(void **state)
{
	(void)state;
	const char *tmp = harness_tmpdir();
	snprintf(seq, sizeof(seq), "%s/seq", tmp);
	harness_synth(seq, "forward", FRAMES, "png", "--size", "320x240", NULL);
	harness_synth(seq, "forward", FRAMES, "mkv", "--size", "320x240", NULL);
	snprintf(images, sizeof(images), "images:%s/images", seq);
	snprintf(mkv, sizeof(mkv), "%s/video.mkv", seq);
	snprintf(video, sizeof(video), "file:%s", mkv);
	snprintf(calib, sizeof(calib), "%s/calib.json", seq);
	snprintf(gt, sizeof(gt), "%s/gt.tum", seq);
	snprintf(frame, sizeof(frame), "%s/images/000003.png", seq);
	/* images:DIR reads DIR/times.txt. */
	snprintf(times, sizeof(times), "%s/images/times.txt", seq);
	char cmd[1024];
	snprintf(cmd, sizeof(cmd), "cp '%s/times.txt' '%s'", seq, times);
	assert_int_equal(system(cmd), 0);
	snprintf(cfg, sizeof(cfg), "%s/mvod.conf", tmp);
	harness_write_file(cfg, "[vo]\nfeatures = 1000\n");
	snprintf(traj, sizeof(traj), "%s/out.tum", tmp);
	snprintf(lcmlog, sizeof(lcmlog), "%s/out.lcmlog", tmp);
	snprintf(url, sizeof(url), "file://%s?mode=w", lcmlog);
	return 0;
}

/* Runs mvod with args (NULL-terminated), failing the test if it was killed. */
static void mvod(struct run_result *r, ...)
{
	char *argv[40] = {(char *)harness_bin("MVOD")};
	int n = 1;
	va_list ap;
	va_start(ap, r);
	for (char *a; n < 39 && (a = va_arg(ap, char *));)
		argv[n++] = a;
	va_end(ap);
	argv[n] = NULL;
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited)
		fail_msg("mvod killed by signal %d: %s", r->status, r->err);
}

static void expect_fail(const struct run_result *r, int status, const char *needle)
{
	if (r->status != status || !strstr(r->err, needle))
		fail_msg("expected exit %d saying \"%s\", got %d: %s", status, needle, r->status, r->err);
}

/* A copy of path beside it (path.bak), to compare byte for byte afterwards. */
static void backup(const char *path)
{
	char cmd[1024];
	snprintf(cmd, sizeof(cmd), "cp -p '%s' '%s.bak'", path, path);
	assert_int_equal(system(cmd), 0);
}

static void assert_unchanged(const char *path)
{
	char cmd[1024];
	snprintf(cmd, sizeof(cmd), "cmp -s '%s' '%s.bak'", path, path);
	if (system(cmd) != 0)
		fail_msg("%s was changed", path);
}

static mode_t file_type(const char *path)
{
	struct stat st;
	assert_int_equal(lstat(path, &st), 0);
	return st.st_mode & S_IFMT;
}

/*
 * Whole events of an LCM log written by mvod, -1 unless it is nothing but whole events (sync
 * word, lengths that fit, event numbers 0, 1, 2, ...); poses counted into *poses.
 */
static int log_events(const char *path, int *poses)
{
	static unsigned char buf[1 << 20];
	int fd = open(path, O_RDONLY);
	assert_true(fd >= 0);
	ssize_t len = read(fd, buf, sizeof(buf));
	close(fd);
	assert_true(len >= 0 && len < (ssize_t)sizeof(buf));
	int n = 0;
	*poses = 0;
	for (ssize_t off = 0; off < len; n++) {
		const unsigned char *p = buf + off;
		uint64_t v[5] = {0};
		static const int width[5] = {4, 8, 8, 4, 4};
		for (int f = 0, at = 0; f < 5; at += width[f++])
			for (int b = 0; b < width[f] && off + at + b < len; b++)
				v[f] = v[f] << 8 | p[at + b];
		if (off + 28 > len || v[0] != 0xEDA1DA01u || v[1] != (uint64_t)n ||
		    off + 28 + (ssize_t)(v[3] + v[4]) > len)
			return -1;
		*poses += v[3] == strlen(MVOD_DEFAULT_POSE_CHANNEL) &&
			  memcmp(p + 28, MVOD_DEFAULT_POSE_CHANNEL, v[3]) == 0;
		off += 28 + (ssize_t)(v[3] + v[4]);
	}
	return n;
}

/* --- output == input --- */

struct input_case {
	const char *flag; /* --trajectory or --plot */
	const char *path; /* the input named as the output */
	const char *source;
	bool with_gt, with_config;
};

static void refuse_input(const struct input_case *c)
{
	struct run_result r;
	char *argv[24] = {(char *)harness_bin("MVOD"), "--source", (char *)c->source, "--calib",
			  calib, "--no-lcm", "--max-frames", "3", (char *)c->flag, (char *)c->path};
	int n = 10;
	if (c->with_gt) {
		argv[n++] = "--gt";
		argv[n++] = gt;
	}
	if (c->with_config) {
		argv[n++] = "--config";
		argv[n++] = cfg;
	}
	argv[n] = NULL;
	backup(c->path);
	assert_int_equal(harness_run(argv, &r), 0);
	expect_fail(&r, 2, "is a file this run reads");
	assert_unchanged(c->path);
}

static void test_output_is_input(void **state)
{
	(void)state;
	const struct input_case cases[] = {
		{"--trajectory", mkv, video, false, false},
		{"--trajectory", frame, images, false, false},
		{"--trajectory", times, images, false, false},
		{"--trajectory", calib, images, false, false},
		{"--plot", calib, images, false, false},
		{"--trajectory", gt, images, true, false},
		{"--plot", gt, images, true, false},
		{"--trajectory", cfg, images, true, true},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++)
		refuse_input(&cases[i]);
	/* Other commands: calib-convert OUT, bench --csv. */
	struct run_result r;
	mvod(&r, "calib-convert", calib, calib, NULL);
	expect_fail(&r, 2, "is a file this run reads");
	assert_unchanged(calib);
	mvod(&r, "bench", "--source", images, "--calib", calib, "--gt", gt, "--csv", gt, NULL);
	expect_fail(&r, 2, "is a file this run reads");
	assert_unchanged(gt);
	/* mvod view --png over the log it reads. */
	char log_url[640];
	snprintf(log_url, sizeof(log_url), "file://%s?mode=r&speed=0", lcmlog);
	mvod(&r, "-q", "--source", images, "--calib", calib, "--max-frames", "3", "--lcm-url", url,
	     NULL);
	assert_int_equal(r.status, 0);
	backup(lcmlog);
	mvod(&r, "view", "--lcm-url", log_url, "--png", lcmlog, NULL);
	expect_fail(&r, 2, "is a file this run reads");
	assert_unchanged(lcmlog);
}

/* views renders of BOARD, 320x240 PNGs, in the test's folder name; its path into dir. */
static void synth_board(const char *name, const char *views, char *dir, size_t len)
{
	snprintf(dir, len, "%s/%s", harness_tmpdir(), name);
	char *synth[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", dir, "--board", BOARD, "--views",
			 (char *)views, "--format", "png", "--size", "320x240", NULL};
	struct run_result r;
	assert_int_equal(harness_run(synth, &r), 0);
	assert_int_equal(r.status, 0);
}

/* --- one file by two names --- */

/*
 * The names an input and an output may share a file by, made next to input: a symlink to it,
 * a hard link to it, and a path through ".." (into the folder .., back out by name).
 */
struct aliases {
	char link[600], hard[600], dotdot[700];
};

static void make_aliases(const char *input, const char *tag, struct aliases *a)
{
	const char *slash = strrchr(input, '/');
	snprintf(a->link, sizeof(a->link), "%s/%s.link", harness_tmpdir(), tag);
	snprintf(a->hard, sizeof(a->hard), "%s/%s.hard", harness_tmpdir(), tag);
	/* DIR/name as DIR/../BASE/name, BASE the last component of DIR. */
	const char *base = slash - 1;
	while (base > input && *base != '/')
		base--;
	snprintf(a->dotdot, sizeof(a->dotdot), "%.*s/..%.*s", (int)(slash - input), input,
		 (int)strlen(base), base);
	unlink(a->link);
	unlink(a->hard);
	assert_int_equal(symlink(input, a->link), 0);
	assert_int_equal(link(input, a->hard), 0);
}

/*
 * mvod ARGS... where "IN" stands for the input's name and "OUT" for the output's: refused
 * with 2 before any work, the input byte for byte as it was.
 */
static void refuse_alias(const char *input, const char *in, const char *out, const char *const *args)
{
	char *argv[24] = {(char *)harness_bin("MVOD")};
	int n = 1;
	for (; *args && n < 23; args++)
		argv[n++] = (char *)(strcmp(*args, "IN") == 0 ? in : strcmp(*args, "OUT") == 0 ? out
											 : *args);
	argv[n] = NULL;
	struct run_result r;
	backup(input);
	assert_int_equal(harness_run(argv, &r), 0);
	if (r.status != 2 || !strstr(r.err, "is a file this run reads"))
		fail_msg("%s as %s, %s as %s: expected exit 2 and a refusal, got %d: %s%s", input,
			 in, input, out, r.status, r.out, r.err);
	assert_unchanged(input);
}

/* Each way of naming one file twice, for the command args: input by an alias, output by its
 * real path; the reverse; a hard link; a ".." path. */
static void refuse_aliases(const char *input, const char *tag, const char *const *args)
{
	struct aliases a;
	make_aliases(input, tag, &a);
	refuse_alias(input, a.link, input, args);
	refuse_alias(input, input, a.link, args);
	refuse_alias(input, input, a.hard, args);
	refuse_alias(input, a.hard, input, args);
	refuse_alias(input, input, a.dotdot, args);
	refuse_alias(input, a.dotdot, input, args);
}

/*
 * An output that is an input, however each is named, for every command that writes: the
 * tests before named the input by its real path only.
 */
static void test_aliases(void **state)
{
	(void)state;
	refuse_aliases(calib, "calib", (const char *const[]){"--source", images, "--calib", "IN",
		       "--no-lcm", "--trajectory", "OUT", NULL});
	refuse_aliases(gt, "gt", (const char *const[]){"--source", images, "--calib", calib, "--gt",
		       "IN", "--no-lcm", "--plot", "OUT", NULL});
	refuse_aliases(gt, "bench", (const char *const[]){"bench", "--source", images, "--calib",
		       calib, "--gt", "IN", "--csv", "OUT", NULL});
	refuse_aliases(calib, "convert", (const char *const[]){"calib-convert", "--to", "mvod", "IN",
		       "OUT", NULL});
	/* calibrate: --out naming one of the frames it reads (the source by a folder's name). */
	char dir[512], src[600], first[600];
	synth_board("alias-board", "12", dir, sizeof(dir));
	snprintf(src, sizeof(src), "images:%s/images", dir);
	snprintf(first, sizeof(first), "%s/images/000003.png", dir);
	struct aliases a;
	make_aliases(first, "frame", &a); /* outside the folder: read as no frame */
	const char *const outs[] = {first, a.link, a.hard, a.dotdot};
	for (size_t i = 0; i < sizeof(outs) / sizeof(outs[0]); i++)
		refuse_alias(first, NULL, outs[i], (const char *const[]){"calibrate", "--source", src,
			     "--board", BOARD, "--out", "OUT", NULL});
	/* The source's folder by a link, the frame named by its real path. */
	char linkdir[600], linksrc[700];
	snprintf(linkdir, sizeof(linkdir), "%s/board-link", harness_tmpdir());
	assert_int_equal(symlink(dir, linkdir), 0);
	snprintf(linksrc, sizeof(linksrc), "images:%s/images", linkdir);
	refuse_alias(first, NULL, first, (const char *const[]){"calibrate", "--source", linksrc,
		     "--board", BOARD, "--out", "OUT", NULL});
}

/* --- a failed start --- */

static void test_failed_start_keeps_outputs(void **state)
{
	(void)state;
	struct run_result r;
	char bad_gt[512];
	snprintf(bad_gt, sizeof(bad_gt), "%s/late.tum", harness_tmpdir());
	/* Ground truth 100 s after every frame: frame 0 finds none and the run fails there. */
	harness_write_file(bad_gt, "100.0 0 0 0 0 0 0 1\n100.1 0 0 1 0 0 0 1\n");
	harness_write_file(traj, "1.0 0 0 0 0 0 0 1\n");
	harness_write_file(lcmlog, "the log of the run before");
	backup(traj);
	backup(lcmlog);
	mvod(&r, "--source", "images:/nonexistent-typo", "--calib", calib, "--trajectory", traj,
	     "--lcm-url", url, NULL);
	expect_fail(&r, 1, "nonexistent-typo");
	mvod(&r, "--source", images, "--calib", "/nonexistent-calib.json", "--trajectory", traj,
	     "--lcm-url", url, NULL);
	expect_fail(&r, 2, "nonexistent-calib.json"); /* 2: the calibration */
	mvod(&r, "--source", images, "--calib", calib, "--gt", bad_gt, "--scale", "gt",
	     "--trajectory", traj, "--lcm-url", url, NULL);
	expect_fail(&r, 1, "frame 0");
	assert_unchanged(traj);
	assert_unchanged(lcmlog);
}

/* --- two instances --- */

static void test_two_instances(void **state)
{
	(void)state;
	char traj2[512], log2[512], url2[600], err_a[512];
	struct run_result r;
	int status;
	snprintf(traj2, sizeof(traj2), "%s/other.tum", harness_tmpdir());
	snprintf(log2, sizeof(log2), "%s/other.lcmlog", harness_tmpdir());
	snprintf(url2, sizeof(url2), "file://%s?mode=w", log2);
	snprintf(err_a, sizeof(err_a), "%s/first.err", harness_tmpdir());
	unlink(traj);
	char *argv[] = {(char *)harness_bin("MVOD"), "-q", "--source", images, "--calib", calib,
			"--trajectory", traj, "--lcm-url", url, NULL};
	pid_t first = harness_spawn(argv, NULL, err_a);
	harness_wait_lines(traj, 2, first);
	/* Stopped mid-run, holding its locks, while the others try; then it goes on. */
	assert_int_equal(kill(first, SIGSTOP), 0);
	mvod(&r, "--source", images, "--calib", calib, "--trajectory", traj, "--lcm-url", url2, NULL);
	expect_fail(&r, 2, "is locked by another process");
	mvod(&r, "--source", images, "--calib", calib, "--trajectory", traj2, "--lcm-url", url, NULL);
	expect_fail(&r, 2, "LCM log");
	assert_true(strstr(r.err, "is locked by another process") != NULL);
	assert_int_equal(kill(first, SIGCONT), 0);
	assert_int_equal(harness_wait(first, &status), 1);
	assert_int_equal(status, 0);
	/* Every line of the first is whole, and its log holds a pose for each. */
	int lines = harness_traj_lines(traj), poses;
	assert_int_equal(lines, FRAMES);
	assert_true(log_events(lcmlog, &poses) > 0);
	assert_int_equal(poses, lines);
}

/* --- symlinks, devices, FIFOs --- */

static void test_symlink_stays_a_link(void **state)
{
	(void)state;
	char real[512], link[512], text[256];
	struct run_result r;
	snprintf(real, sizeof(real), "%s/real-calib.json", harness_tmpdir());
	snprintf(link, sizeof(link), "%s/link-calib.json", harness_tmpdir());
	harness_write_file(real, "old");
	unlink(link);
	assert_int_equal(symlink("real-calib.json", link), 0);
	mvod(&r, "calib-convert", calib, link, NULL);
	assert_int_equal(r.status, 0);
	assert_int_equal(file_type(link), S_IFLNK);
	harness_read_file(real, text, sizeof(text));
	assert_non_null(strstr(text, "mvod-calibration/1"));
}

static void test_csv_into_char_device(void **state)
{
	(void)state;
	char null[512];
	struct run_result r;
	snprintf(null, sizeof(null), "%s/null", harness_tmpdir());
	unlink(null);
	if (mknod(null, S_IFCHR | 0666, makedev(1, 3)) != 0)
		skip(); /* not root: no device nodes */
	mvod(&r, "bench", "-q", "--source", images, "--calib", calib, "--gt", gt, "--csv", null,
	     "--max-frames", "8", NULL);
	if (r.status != 0)
		fail_msg("bench --csv DEVICE: %d %s", r.status, r.err);
	assert_int_equal(file_type(null), S_IFCHR);
}

/* A FIFO with a reader gets the file; the FIFO stays. */
static void test_fifo_written_into(void **state)
{
	(void)state;
	char fifo[512], got[512], text[4096];
	struct run_result r;
	snprintf(fifo, sizeof(fifo), "%s/calib-fifo.json", harness_tmpdir());
	snprintf(got, sizeof(got), "%s/fifo.out", harness_tmpdir());
	unlink(fifo);
	assert_int_equal(mkfifo(fifo, 0600), 0);
	char *cat[] = {"/bin/cat", fifo, NULL};
	pid_t reader = harness_spawn(cat, got, NULL);
	/* cat's open blocks until a writer comes; this one opens and closes without writing. */
	int hold = open(fifo, O_RDWR | O_CLOEXEC);
	assert_true(hold >= 0);
	mvod(&r, "calib-convert", calib, fifo, NULL);
	close(hold);
	assert_int_equal(r.status, 0);
	int status;
	assert_int_equal(harness_wait(reader, &status), 1);
	harness_read_file(got, text, sizeof(text));
	assert_non_null(strstr(text, "mvod-calibration/1"));
	assert_int_equal(file_type(fifo), S_IFIFO);
}

/* Nobody at the other end: refused at once, where mvod once blocked for ever. */
static void test_fifo_without_peer(void **state)
{
	(void)state;
	char fifo[512];
	struct run_result r;
	snprintf(fifo, sizeof(fifo), "%s/lonely.fifo", harness_tmpdir());
	unlink(fifo);
	assert_int_equal(mkfifo(fifo, 0600), 0);
	mvod(&r, "--source", images, "--calib", calib, "--no-lcm", "--trajectory", fifo, NULL);
	expect_fail(&r, 2, "is a FIFO that no process reads");
	mvod(&r, "--source", images, "--config", fifo, "--no-lcm", NULL);
	expect_fail(&r, 2, "is a FIFO that no process writes into");
	assert_int_equal(file_type(fifo), S_IFIFO);
}

/* --- SIGHUP at start-up --- */

/*
 * mvod reads its configuration from a FIFO this test holds: it is blocked in start-up, before
 * any library or source loads, when SIGHUP comes. It must live on and run.
 */
static void test_sighup_at_start(void **state)
{
	(void)state;
	char fifo[512];
	snprintf(fifo, sizeof(fifo), "%s/conf.fifo", harness_tmpdir());
	unlink(fifo);
	assert_int_equal(mkfifo(fifo, 0600), 0);
	/* A writer (not inherited), so mvod's read waits for the text. */
	int hold = open(fifo, O_RDWR | O_CLOEXEC);
	assert_true(hold >= 0);
	char *argv[] = {(char *)harness_bin("MVOD"), "-q", "--config", fifo, "--source", images,
			"--calib", calib, "--no-lcm", "--max-frames", "2", NULL};
	pid_t pid = harness_spawn(argv, NULL, NULL);
	harness_wait_open(pid, fifo);
	assert_int_equal(kill(pid, SIGHUP), 0);
	const char text[] = "[vo]\nfeatures = 1000\n";
	assert_int_equal(write(hold, text, sizeof(text) - 1), (ssize_t)sizeof(text) - 1);
	close(hold);
	int status;
	if (harness_wait(pid, &status) != 1)
		fail_msg("mvod killed by signal %d", status);
	assert_int_equal(status, 0);
}

/* --- honest LCM logs --- */

/* A log on a tiny file system, full after a few events: exit 1, one message, whole events. */
static void test_log_on_full_disk(void **state)
{
	(void)state;
	char mnt[512], fill[600], full_log[600], full_url[640];
	struct run_result r;
	snprintf(mnt, sizeof(mnt), "%s/tiny", harness_tmpdir());
	mkdir(mnt, 0700);
	if (geteuid() != 0 || mount("tmpfs", mnt, "tmpfs", 0, "size=64k") != 0)
		skip();
	snprintf(fill, sizeof(fill), "%s/fill", mnt);
	snprintf(full_log, sizeof(full_log), "%s/out.lcmlog", mnt);
	snprintf(full_url, sizeof(full_url), "file://%s?mode=w", full_log);
	char cmd[1024];
	/* 60 of the 64 KiB: a page (4 KiB, ~30 events of ~130 bytes) is left for the log. */
	snprintf(cmd, sizeof(cmd), "head -c 61440 /dev/zero > '%s'", fill);
	int sys = system(cmd);
	/* A status with every frame: ~300 bytes of log per frame, the page is full by frame 14. */
	mvod(&r, "--source", images, "--calib", calib, "--lcm-url", full_url, "--status-rate", "100",
	     NULL);
	int poses, events = log_events(full_log, &poses);
	umount(mnt);
	assert_int_equal(sys, 0);
	/* Once: the first of pose or status to fail says it. */
	expect_fail(&r, 1, "over LCM failed");
	assert_null(strstr(strstr(r.err, "over LCM failed") + 1, "over LCM failed"));
	assert_true(events > 0);
	assert_true(poses < FRAMES);
}

/* A device that refuses every write (mknod'ed like /dev/full): the same, from the first event. */
static void test_log_on_full_device(void **state)
{
	(void)state;
	char full[512], full_url[600];
	struct run_result r;
	snprintf(full, sizeof(full), "%s/full", harness_tmpdir());
	unlink(full);
	if (mknod(full, S_IFCHR | 0666, makedev(1, 7)) != 0)
		skip();
	snprintf(full_url, sizeof(full_url), "file://%s?mode=w", full);
	mvod(&r, "--source", images, "--calib", calib, "--trajectory", traj, "--lcm-url", full_url,
	     NULL);
	expect_fail(&r, 1, "frame 0: publishing the pose over LCM failed");
	assert_int_equal(file_type(full), S_IFCHR);
	/* The trajectory, a separate output, is whole. */
	assert_int_equal(harness_traj_lines(traj), FRAMES);
}

struct fake_lcm {
	int poses_refused;
	int32_t last_faults;
	int statuses;
};

/* The publish seam: poses (v1) refused, statuses (v1) decoded, the v2 twins taken as sent. */
static int fake_send(void *ctx, const char *channel, const void *buf, size_t len)
{
	struct fake_lcm *f = ctx;
	if (strcmp(channel, MVOD_DEFAULT_POSE_CHANNEL) == 0) {
		f->poses_refused++;
		return -EIO;
	}
	if (strcmp(channel, MVOD_DEFAULT_STATUS_CHANNEL) != 0)
		return 0;
	mvod_status_t msg;
	assert_true(mvod_status_t_decode(buf, 0, (int)len, &msg) > 0);
	f->last_faults = msg.faults;
	f->statuses++;
	mvod_status_t_decode_cleanup(&msg);
	return 0;
}

/* FAULT_PUBLISH, end to end through the run loop, reaches the status that still goes out. */
static void test_fault_publish_in_status(void **state)
{
	(void)state;
	struct fake_lcm f = {0};
	struct mvod_ipc *ipc = NULL;
	assert_int_equal(mvod_ipc_create_with(fake_send, &f, NULL, NULL, &ipc), 0);
	struct mvod_run_opts o;
	mvod_run_opts_default(&o);
	o.source = images;
	o.calib = calib;
	o.max_frames = 5;
	struct mvod_run_summary sum;
	assert_int_equal(mvod_run(&o, ipc, NULL, &sum), 0);
	mvod_ipc_destroy(ipc);
	assert_int_equal(f.poses_refused, 5);
	assert_true(f.statuses >= 1);
	assert_true(f.last_faults & MVOD_STATUS_T_FAULT_PUBLISH);
}

/* --- signals --- */

/*
 * SIGINT and SIGTERM (the second ends mvod at once) after a random number of lines, seeded: every
 * trajectory line and every log event is whole, and the log lost at most the event in flight.
 */
static void test_double_stop_random(void **state)
{
	(void)state;
	srand(20261201);
	char *argv[] = {(char *)harness_bin("MVOD"), "-q", "--source", images, "--calib", calib,
			"--trajectory", traj, "--lcm-url", url, NULL};
	for (int round = 0; round < 4; round++) {
		unlink(traj);
		unlink(lcmlog);
		int lines = 1 + rand() % (FRAMES / 2);
		pid_t pid = harness_spawn(argv, NULL, NULL);
		harness_wait_lines(traj, lines, pid);
		/* Two different signals: pending together they are not merged into one. */
		kill(pid, SIGINT);
		kill(pid, SIGTERM);
		int status;
		harness_wait(pid, &status);
		int n = harness_traj_lines(traj), poses;
		if (log_events(lcmlog, &poses) < 0)
			fail_msg("round %d: the LCM log ends inside an event", round);
		/* Each pose goes to the log before its line: the log holds at least as many. */
		if (n < lines || poses < n)
			fail_msg("round %d: %d lines (signalled at %d), %d poses logged", round, n,
				 lines, poses);
	}
}

/* --- calibrate interrupted --- */

/* A number from a /proc/PID file's "key: value" line (base 10 or 16), -1 once pid is gone. */
static long long proc_value(pid_t pid, const char *file, const char *key, int base)
{
	char path[64], line[256];
	long long v = -1;
	size_t klen = strlen(key);
	snprintf(path, sizeof(path), "/proc/%d/%s", (int)pid, file);
	FILE *f = fopen(path, "r");
	while (f && v < 0 && fgets(line, sizeof(line), f))
		if (strncmp(line, key, klen) == 0)
			v = strtoll(line + klen, NULL, base);
	if (f)
		fclose(f);
	return v;
}

/*
 * Ctrl-C halfway through the views of a recorded file: a calibration on half of it would replace
 * the good one. Nothing is written; exit 1 saying so.
 */
static void test_calibrate_interrupted(void **state)
{
	(void)state;
	char dir[512], src[600], out[512], report[512], err_path[512], text[4096];
	struct stat st;
	synth_board("board", "40", dir, sizeof(dir));
	snprintf(src, sizeof(src), "images:%s/images", dir);
	snprintf(out, sizeof(out), "%s/good.json", harness_tmpdir());
	snprintf(report, sizeof(report), "%s/good.png", harness_tmpdir());
	snprintf(err_path, sizeof(err_path), "%s/calibrate.err", harness_tmpdir());
	harness_write_file(out, "the good calibration");
	harness_write_file(report, "the good report");
	backup(out);
	backup(report);
	snprintf(text, sizeof(text), "%s/images/000000.png", dir);
	assert_int_equal(stat(text, &st), 0);
	char *argv[] = {(char *)harness_bin("MVOD"), "calibrate", "--source", src, "--board", BOARD,
			"--out", out, "--report", report, NULL};
	pid_t pid = harness_spawn(argv, NULL, err_path);
	/* Its Ctrl-C handler is in place (SigCgt bit 1), right before reading starts... */
	long long cgt = 0, start = -1, now = 0;
	while (cgt >= 0 && !(cgt & 2))
		cgt = proc_value(pid, "status", "SigCgt:", 16), usleep(1000);
	/* ...then half the frames, each read whole (rchar): enough views, 20 before the end. */
	while (cgt >= 0 && now >= 0 && now - start < (BOARD_VIEWS / 2) * (long long)st.st_size) {
		now = proc_value(pid, "io", "rchar:", 10);
		start = start < 0 ? now : start;
		usleep(1000);
	}
	kill(pid, SIGINT);
	int status;
	assert_int_equal(harness_wait(pid, &status), 1);
	harness_read_file(err_path, text, sizeof(text));
	if (status != 1 || !strstr(text, "nothing written"))
		fail_msg("expected exit 1 and \"nothing written\", got %d: %s", status, text);
	assert_unchanged(out);
	assert_unchanged(report);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_output_is_input),
		cmocka_unit_test(test_aliases),
		cmocka_unit_test(test_failed_start_keeps_outputs),
		cmocka_unit_test(test_two_instances),
		cmocka_unit_test(test_symlink_stays_a_link),
		cmocka_unit_test(test_csv_into_char_device),
		cmocka_unit_test(test_fifo_written_into),
		cmocka_unit_test(test_fifo_without_peer),
		cmocka_unit_test(test_sighup_at_start),
		cmocka_unit_test(test_log_on_full_disk),
		cmocka_unit_test(test_log_on_full_device),
		cmocka_unit_test(test_fault_publish_in_status),
		cmocka_unit_test(test_double_stop_random),
		cmocka_unit_test(test_calibrate_interrupted),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}

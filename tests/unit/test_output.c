/*
 * The output policy (util/output.h) on a table of paths in a temporary folder: what each kind
 * of thing at a path becomes, through symlinks of every shape; the stream outputs' lock and
 * deferred truncation; mvod_write_replace keeping links, devices and permissions.
 */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"
#include "util/atomic_file.h"
#include "util/output.h"

/* Paths here are a short temporary folder plus a name: none comes near its buffer. */
#pragma GCC diagnostic ignored "-Wformat-truncation"

static char dir[256];

static const char *at(const char *name)
{
	static char paths[8][512];
	static int next;
	char *p = paths[next++ % 8];
	snprintf(p, 512, "%s/%s", dir, name);
	return p;
}

static int setup(void **state)
{
	(void)state;
	snprintf(dir, sizeof(dir), "%s", harness_tmpdir());
	harness_write_file(at("file.txt"), "old");
	harness_write_file(at("input.txt"), "read by the run");
	mkdir(at("sub"), 0755);
	harness_write_file(at("sub/deep.txt"), "deep");
	mkfifo(at("fifo"), 0600);
	if (symlink("file.txt", at("rel-link")) || symlink(at("file.txt"), at("abs-link")) ||
	    symlink("rel-link", at("link-to-link")) || symlink("missing.txt", at("dangling")) ||
	    symlink("loop-b", at("loop-a")) || symlink("loop-a", at("loop-b")) ||
	    symlink("sub", at("dir-link")) || symlink("../input.txt", at("sub/up-to-input")) ||
	    symlink("fifo", at("fifo-link")))
		return -1;
	/* Device nodes of our own (root only): a /dev/null and a loop disk's numbers. */
	mknod(at("null"), S_IFCHR | 0666, makedev(1, 3));
	mknod(at("disk"), S_IFBLK | 0600, makedev(7, 0));
	int s = socket(AF_UNIX, SOCK_STREAM, 0);
	struct sockaddr_un addr = {.sun_family = AF_UNIX};
	snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", at("sock"));
	if (s < 0 || bind(s, (struct sockaddr *)&addr, sizeof(addr)) != 0)
		return -1;
	close(s);
	return mvod_input_note(at("input.txt"));
}

static int teardown(void **state)
{
	mvod_inputs_forget();
	return harness_teardown(state);
}

struct path_case {
	const char *name;    /* under dir; NULL for the literal path below */
	int ret;             /* 0 or -errno */
	enum mvod_output_kind kind;
	const char *target;  /* the name written, under dir (when ret is 0) */
	const char *say;     /* in the reason (when ret is not 0) */
};

static void test_path_table(void **state)
{
	(void)state;
	const struct path_case cases[] = {
		{"new.txt", 0, MVOD_OUTPUT_NEW, "new.txt", NULL},
		{"file.txt", 0, MVOD_OUTPUT_REGULAR, "file.txt", NULL},
		{"rel-link", 0, MVOD_OUTPUT_REGULAR, "file.txt", NULL},
		{"link-to-link", 0, MVOD_OUTPUT_REGULAR, "file.txt", NULL},
		{"dangling", 0, MVOD_OUTPUT_NEW, "missing.txt", NULL},
		{"dir-link/deep.txt", 0, MVOD_OUTPUT_REGULAR, "dir-link/deep.txt", NULL},
		{"fifo", 0, MVOD_OUTPUT_FIFO, "fifo", NULL},
		{"fifo-link", 0, MVOD_OUTPUT_FIFO, "fifo", NULL},
		{"input.txt", -EEXIST, 0, NULL, "a file this run reads"},
		{"sub/up-to-input", -EEXIST, 0, NULL, "a file this run reads"},
		{"sub", -EISDIR, 0, NULL, "is a directory"},
		{"dir-link", -EISDIR, 0, NULL, "is a directory"},
		{"sock", -EPERM, 0, NULL, "is a socket"},
		{"loop-a", -ELOOP, 0, NULL, "cannot follow the symlink"},
		{"no-such-dir/x.txt", -ENOENT, 0, NULL, "cannot write in"},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		const struct path_case *c = &cases[i];
		char target[PATH_MAX] = "", err[512] = "";
		enum mvod_output_kind kind = (enum mvod_output_kind)-1;
		int ret = mvod_output_check("--out", at(c->name), target, sizeof(target), &kind, err,
					    sizeof(err));
		if (ret != c->ret)
			fail_msg("%s: %d, expected %d (%s)", c->name, ret, c->ret, err);
		if (ret) {
			if (!strstr(err, c->say) || !strstr(err, "--out") || strchr(err, '\n'))
				fail_msg("%s: \"%s\" does not say \"%s\" in one line", c->name, err,
					 c->say);
			continue;
		}
		struct stat want, got;
		assert_int_equal(kind, c->kind);
		if (kind == MVOD_OUTPUT_NEW) {
			assert_non_null(strstr(target, c->target));
			continue;
		}
		/* The same file as the expected name, however the link spelt it. */
		assert_int_equal(stat(at(c->target), &want), 0);
		assert_int_equal(stat(target, &got), 0);
		assert_true(want.st_ino == got.st_ino && want.st_dev == got.st_dev);
	}
}

/* Device nodes: a character device is written into; a disk is refused. Root only (mknod). */
static void test_devices(void **state)
{
	(void)state;
	char target[PATH_MAX], err[512];
	enum mvod_output_kind kind;
	struct stat st;
	if (lstat(at("null"), &st) != 0 || lstat(at("disk"), &st) != 0)
		skip();
	assert_int_equal(mvod_output_check("--csv", at("null"), target, sizeof(target), &kind, err,
					   sizeof(err)), 0);
	assert_int_equal(kind, MVOD_OUTPUT_DEVICE);
	assert_int_equal(mvod_output_check("--csv", at("disk"), target, sizeof(target), &kind, err,
					   sizeof(err)), -EPERM);
	assert_non_null(strstr(err, "block device"));
	assert_int_equal(mvod_write_replace(at("null"), "x", 1), 0);
	assert_int_equal(lstat(at("null"), &st), 0);
	assert_true(S_ISCHR(st.st_mode));
	assert_int_equal(mvod_write_replace(at("disk"), "x", 1), -EPERM);
}

/* Replacing through a link: the link stays, its target gets the text and keeps its mode. */
static void test_replace_keeps_link_and_mode(void **state)
{
	(void)state;
	char text[64];
	struct stat st;
	assert_int_equal(chmod(at("file.txt"), 0600), 0);
	assert_int_equal(mvod_write_replace(at("link-to-link"), "new", 3), 0);
	assert_int_equal(lstat(at("link-to-link"), &st), 0);
	assert_true(S_ISLNK(st.st_mode));
	harness_read_file(at("file.txt"), text, sizeof(text));
	assert_string_equal(text, "new");
	assert_int_equal(stat(at("file.txt"), &st), 0);
	assert_int_equal(st.st_mode & 07777, 0600);
	assert_int_equal(mvod_write_replace(at("input.txt"), "x", 1), -EEXIST);
	assert_int_equal(mvod_write_replace(at("sub"), "x", 1), -EISDIR);
	/* A FIFO nobody reads: refused at once, never blocking. */
	assert_int_equal(mvod_write_replace(at("fifo"), "x", 1), -ENXIO);
}

/* A stream: the old text stays until the first record; a second writer is refused. */
static void test_stream_lock_and_late_truncation(void **state)
{
	(void)state;
	struct mvod_output *a = NULL, *b = NULL;
	char err[512] = "", text[64];
	harness_write_file(at("stream.txt"), "before\n");
	assert_int_equal(mvod_output_open("trajectory", at("stream.txt"), &a, err, sizeof(err)), 0);
	harness_read_file(at("stream.txt"), text, sizeof(text));
	assert_string_equal(text, "before\n");
	assert_int_equal(mvod_output_open("trajectory", at("stream.txt"), &b, err, sizeof(err)),
			 -EWOULDBLOCK);
	assert_non_null(strstr(err, "is locked by another process"));
	assert_int_equal(mvod_output_write(a, "one\n", 4), 0);
	assert_int_equal(mvod_output_write(a, "two\n", 4), 0);
	/* Not rotated: reopening keeps the same file, appending. */
	assert_int_equal(mvod_output_reopen(a, err, sizeof(err)), 0);
	assert_int_equal(mvod_output_write(a, "three\n", 6), 0);
	assert_int_equal(mvod_output_close(a), 0);
	harness_read_file(at("stream.txt"), text, sizeof(text));
	assert_string_equal(text, "one\ntwo\nthree\n");
	/* Closed without a record: the file is as it was. */
	assert_int_equal(mvod_output_open("trajectory", at("stream.txt"), &a, err, sizeof(err)), 0);
	assert_int_equal(mvod_output_close(a), 0);
	harness_read_file(at("stream.txt"), text, sizeof(text));
	assert_string_equal(text, "one\ntwo\nthree\n");
	assert_int_equal(mvod_output_open("trajectory", at("fifo"), &a, err, sizeof(err)), -ENXIO);
	assert_non_null(strstr(err, "no process reads"));
}

/* Rotation: after a rename, the name is a new file, and the old one is complete. */
static void test_stream_rotation(void **state)
{
	(void)state;
	struct mvod_output *o = NULL;
	char err[512] = "", text[64];
	unlink(at("rot.txt"));
	assert_int_equal(mvod_output_open("LCM log", at("rot.txt"), &o, err, sizeof(err)), 0);
	assert_int_equal(mvod_output_write(o, "a\n", 2), 0);
	assert_int_equal(rename(at("rot.txt"), at("rot.txt.1")), 0);
	assert_int_equal(mvod_output_reopen(o, err, sizeof(err)), 0);
	assert_int_equal(mvod_output_write(o, "b\n", 2), 0);
	assert_int_equal(mvod_output_close(o), 0);
	harness_read_file(at("rot.txt.1"), text, sizeof(text));
	assert_string_equal(text, "a\n");
	harness_read_file(at("rot.txt"), text, sizeof(text));
	assert_string_equal(text, "b\n");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_path_table),
		cmocka_unit_test(test_devices),
		cmocka_unit_test(test_replace_keeps_link_and_mode),
		cmocka_unit_test(test_stream_lock_and_late_truncation),
		cmocka_unit_test(test_stream_rotation),
	};
	return cmocka_run_group_tests(tests, setup, teardown);
}

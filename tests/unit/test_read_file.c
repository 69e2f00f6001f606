/*
 * mvod_read_file: the whole file or a reason; the size bound counted to the byte; the input
 * path's refusals (a directory, a FIFO or a device where a regular file is meant).
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#include "util/input.h"
#include "util/read_file.h"

static char path[256];

static int setup(void **state)
{
	(void)state;
	snprintf(path, sizeof(path), "%s/f", harness_tmpdir());
	return 0;
}

/* Longer than the first 4096-byte buffer, so the growth is on the path. */
static char *text_of(size_t n)
{
	char *t = malloc(n + 1);
	assert_non_null(t);
	for (size_t i = 0; i < n; i++)
		t[i] = (char)('a' + i % 26);
	t[n] = '\0';
	return t;
}

static void test_whole_file(void **state)
{
	(void)state;
	static const size_t sizes[] = {0, 1, 4095, 4096, 4097, 10000};
	for (size_t i = 0; i < sizeof(sizes) / sizeof(sizes[0]); i++) {
		char *want = text_of(sizes[i]), *got = NULL, err[256] = "";
		size_t len = 1234;
		harness_write_file(path, want);
		if (mvod_read_file(path, 10000, "test file", 0, &got, &len, err, sizeof(err)))
			fail_msg("%zu bytes: %s", sizes[i], err);
		assert_int_equal(len, sizes[i]);
		assert_string_equal(got, want); /* NUL-terminated at len */
		free(got);
		free(want);
	}
}

static void test_refusals(void **state)
{
	(void)state;
	char *t = text_of(10001), *got = NULL, err[256] = "";
	harness_write_file(path, t);
	free(t);
	assert_int_equal(mvod_read_file(path, 10000, "test file", 0, &got, NULL, err, sizeof(err)), -EFBIG);
	assert_non_null(strstr(err, "larger than 10000 bytes: not a test file"));
	assert_null(got);
	assert_int_equal(mvod_read_file("/nonexistent/f", 10, "test file", 0, &got, NULL, err, sizeof(err)),
			 -ENOENT);
	assert_non_null(strstr(err, "cannot read /nonexistent/f"));
	assert_int_equal(mvod_read_file(harness_tmpdir(), 10, "test file", 0, &got, NULL, err, sizeof(err)),
			 -EISDIR);
	assert_null(got);
}

/* A FIFO is taken with MVOD_INPUT_STREAM when a process writes into it, never without. */
static void test_fifo(void **state)
{
	(void)state;
	char fifo[300], *got = NULL, err[256] = "";
	snprintf(fifo, sizeof(fifo), "%s/fifo", harness_tmpdir());
	unlink(fifo);
	assert_int_equal(mkfifo(fifo, 0600), 0);
	int w = open(fifo, O_RDWR | O_CLOEXEC); /* a writer: the text waits in the pipe */
	assert_true(w >= 0);
	assert_int_equal(write(w, "x = 1\n", 6), 6);
	assert_int_equal(mvod_read_file(fifo, 100, "test file", 0, &got, NULL, err, sizeof(err)),
			 -EINVAL);
	assert_non_null(strstr(err, "is a FIFO: the test file must be a regular file"));
	pid_t pid = fork();
	if (pid == 0) { /* the writer, which ends after a while: the end of the text */
		usleep(100000);
		_exit(0);
	}
	close(w);
	size_t len = 0;
	int ret = mvod_read_file(fifo, 100, "test file", MVOD_INPUT_STREAM, &got, &len, err,
				 sizeof(err));
	waitpid(pid, NULL, 0);
	if (ret)
		fail_msg("%s", err);
	assert_string_equal(got, "x = 1\n");
	free(got);
	/* Nobody writes: refused at once, never blocking. */
	assert_int_equal(mvod_read_file(fifo, 100, "test file", MVOD_INPUT_STREAM, &got, NULL, err,
					sizeof(err)), -ENXIO);
	assert_non_null(strstr(err, "is a FIFO that no process writes into"));
}

/* /dev/zero is endless: a device is refused before a byte is read. */
static void test_device(void **state)
{
	(void)state;
	char *got = NULL, err[256] = "";
	assert_int_equal(mvod_read_file("/dev/zero", 1 << 20, "test file", MVOD_INPUT_STREAM, &got,
					NULL, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "/dev/zero is a character device: the test file must be a "
				    "regular file"));
	assert_null(got);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_whole_file),
		cmocka_unit_test(test_refusals),
		cmocka_unit_test(test_fifo),
		cmocka_unit_test(test_device),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}

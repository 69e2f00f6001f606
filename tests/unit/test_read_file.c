/*
 * mvod_read_file: the whole file or a reason; the size bound counted to the byte.
 * mvod_read_lines: each line that is not blank or a comment, with its number, ends cut off;
 * the callback's stop and error; the file's own errors.
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"

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
		if (mvod_read_file(path, 10000, "test file", &got, &len, err, sizeof(err)))
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
	assert_int_equal(mvod_read_file(path, 10000, "test file", &got, NULL, err, sizeof(err)), -EFBIG);
	assert_non_null(strstr(err, "larger than 10000 bytes: not a test file"));
	assert_null(got);
	assert_int_equal(mvod_read_file("/nonexistent/f", 10, "test file", &got, NULL, err, sizeof(err)),
			 -ENOENT);
	assert_non_null(strstr(err, "cannot read /nonexistent/f"));
	assert_int_equal(mvod_read_file(harness_tmpdir(), 10, "test file", &got, NULL, err, sizeof(err)),
			 -EISDIR);
	assert_null(got);
}

/* What the callback saw: "lineno:text|" per line, and when it stops or fails. */
struct seen {
	char text[512];
	size_t stop_at, fail_at;
};

static int see(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct seen *s = ctx;
	size_t len = strlen(s->text);
	snprintf(s->text + len, sizeof(s->text) - len, "%zu:%s|", lineno, line);
	if (lineno == s->fail_at) {
		snprintf(err, errlen, "line %zu is bad", lineno);
		return -EINVAL;
	}
	return lineno == s->stop_at;
}

static void test_lines(void **state)
{
	(void)state;
	/* CRLF and LF ends, blank and whitespace-only lines, comments (indented too), no final end. */
	harness_write_file(path, "a b\r\n\n  \t\n# c\n  # d\n  e\n\r\nf");
	struct seen s = {.stop_at = 0};
	char err[256] = "";
	assert_int_equal(mvod_read_lines(path, see, &s, err, sizeof(err)), 0);
	assert_string_equal(s.text, "1:a b|6:  e|8:f|");
	/* > 0 stops the reading without an error. */
	s = (struct seen){.stop_at = 6};
	assert_int_equal(mvod_read_lines(path, see, &s, err, sizeof(err)), 0);
	assert_string_equal(s.text, "1:a b|6:  e|");
	/* An error ends it, handed back as the callback gave it. */
	s = (struct seen){.fail_at = 6};
	assert_int_equal(mvod_read_lines(path, see, &s, err, sizeof(err)), -EINVAL);
	assert_string_equal(s.text, "1:a b|6:  e|");
	assert_string_equal(err, "line 6 is bad");
	/* A line longer than any first buffer comes whole. */
	char *t = text_of(10000);
	harness_write_file(path, t);
	s = (struct seen){.stop_at = 0};
	assert_int_equal(mvod_read_lines(path, see, &s, err, sizeof(err)), 0);
	assert_int_equal(strlen(s.text), sizeof(s.text) - 1);
	assert_memory_equal(s.text + 2, t, sizeof(s.text) - 3);
	free(t);
}

static void test_lines_refused(void **state)
{
	(void)state;
	struct seen s = {.stop_at = 0};
	char err[256] = "";
	assert_int_equal(mvod_read_lines("/nonexistent/f", see, &s, err, sizeof(err)), -ENOENT);
	assert_non_null(strstr(err, "cannot read /nonexistent/f"));
	/* A directory opens, then fails to read: an error, not an empty file. */
	assert_int_equal(mvod_read_lines(harness_tmpdir(), see, &s, err, sizeof(err)), -EISDIR);
	assert_non_null(strstr(err, "Is a directory"));
	assert_string_equal(s.text, "");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_whole_file),
		cmocka_unit_test(test_refusals),
		cmocka_unit_test(test_lines),
		cmocka_unit_test(test_lines_refused),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}

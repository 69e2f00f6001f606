/*
 * The line reader (util/lines.h): each line that is not blank or a comment, with its number,
 * ends cut off; the callback's stop and error; a line too long or a byte no text holds is an
 * error naming the file and the line, never the end of the file; FIFOs, devices and folders
 * are refused before a byte is read; what it reads is an input no output may be.
 */
#include <errno.h>
#include <fcntl.h>
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

#include "util/lines.h"
#include "util/output.h"

static char path[256];

static int setup(void **state)
{
	(void)state;
	snprintf(path, sizeof(path), "%s/f", harness_tmpdir());
	return 0;
}

static void write_bytes(const char *p, const char *data, size_t n)
{
	FILE *f = fopen(p, "wb");
	assert_non_null(f);
	assert_int_equal(fwrite(data, 1, n, f), n);
	fclose(f);
}

/* What the callback saw: "lineno:text|" per line, and when it stops or fails. */
struct seen {
	char text[512];
	size_t stop_at, fail_at, lines;
};

static int see(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct seen *s = ctx;
	size_t len = strlen(s->text);
	snprintf(s->text + len, sizeof(s->text) - len, "%zu:%s|", lineno, line);
	s->lines++;
	if (lineno == s->fail_at) {
		snprintf(err, errlen, "line %zu is bad", lineno);
		return -EINVAL;
	}
	return lineno == s->stop_at;
}

static int each(struct seen *s, char *err, size_t errlen)
{
	return mvod_lines_each(path, "test file", see, s, err, errlen);
}

static void test_lines(void **state)
{
	(void)state;
	/* CRLF and LF ends, blank and whitespace-only lines, comments (indented too), no final
	 * end, a byte order mark. */
	harness_write_file(path, "\xEF\xBB\xBF" "a b\r\n\n  \t\n# c\n  # d\n  e\n\r\nf");
	struct seen s = {.stop_at = 0};
	char err[256] = "";
	assert_int_equal(each(&s, err, sizeof(err)), 0);
	assert_string_equal(s.text, "1:a b|6:  e|8:f|");
	/* > 0 stops the reading without an error. */
	s = (struct seen){.stop_at = 6};
	assert_int_equal(each(&s, err, sizeof(err)), 0);
	assert_string_equal(s.text, "1:a b|6:  e|");
	/* An error ends it, handed back as the callback gave it. */
	s = (struct seen){.fail_at = 6};
	assert_int_equal(each(&s, err, sizeof(err)), -EINVAL);
	assert_string_equal(s.text, "1:a b|6:  e|");
	assert_string_equal(err, "line 6 is bad");
	/* Empty: no line, no error. */
	harness_write_file(path, "");
	s = (struct seen){.stop_at = 0};
	assert_int_equal(each(&s, err, sizeof(err)), 0);
	assert_int_equal(s.lines, 0);
}

/* Lines of every length across the buffer's refills, each whole and in order. */
static void test_refills(void **state)
{
	(void)state;
	size_t n = 3000, total = 0;
	char *text = malloc(n * 200);
	assert_non_null(text);
	for (size_t i = 0; i < n; i++)
		total += (size_t)sprintf(text + total, "%zu %.*s\n", i, (int)(i % 190),
					 "xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx"
					 "xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx"
					 "xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx");
	write_bytes(path, text, total);
	struct mvod_lines *l;
	char err[256] = "", *line;
	size_t lineno, k = 0;
	assert_int_equal(mvod_lines_open(path, "test file", &l, err, sizeof(err)), 0);
	int ret;
	while ((ret = mvod_lines_next(l, &line, &lineno, err, sizeof(err))) > 0) {
		assert_int_equal(lineno, k + 1);
		char want[16];
		int w = snprintf(want, sizeof(want), "%zu ", k);
		assert_memory_equal(line, want, (size_t)w);
		assert_int_equal(strlen(line), (size_t)w + k % 190);
		k++;
	}
	assert_int_equal(ret, 0);
	assert_int_equal(k, n);
	mvod_lines_close(l);
	free(text);
}

/*
 * The longest line that fits comes whole; one byte more is an error naming the file and the
 * line (the reader once took it for the end of the file).
 */
static void test_too_long(void **state)
{
	(void)state;
	size_t n = MVOD_LINE_MAX - 1; /* the line, then its "\n": the buffer's MVOD_LINE_MAX */
	char *text = malloc(2 * MVOD_LINE_MAX + 16);
	assert_non_null(text);
	memcpy(text, "1\n", 2);
	memset(text + 2, 'a', n);
	memcpy(text + 2 + n, "\n2\n", 3);
	write_bytes(path, text, n + 5);
	struct seen s = {.stop_at = 0};
	char err[512] = "";
	assert_int_equal(each(&s, err, sizeof(err)), 0);
	assert_int_equal(s.lines, 3);
	text[2 + n] = 'a'; /* line 2 one byte longer: "1\n" "aaa...a" "a" "2\n" */
	memcpy(text + 3 + n, "\n3\n", 3);
	write_bytes(path, text, n + 6);
	s = (struct seen){.stop_at = 0};
	assert_int_equal(each(&s, err, sizeof(err)), -E2BIG);
	assert_int_equal(s.lines, 1);
	char want[512];
	snprintf(want, sizeof(want), "%s line 2 is longer than %d bytes: no line of a test file is",
		 path, MVOD_LINE_MAX - 1);
	assert_non_null(strstr(err, want));
	free(text);
}

/* A NUL or another control character: no text, whatever comes before it on the line. */
static void test_not_text(void **state)
{
	(void)state;
	static const char nul[] = "12.5\n12.6\0garbage\n12.7\n";
	write_bytes(path, nul, sizeof(nul) - 1);
	struct seen s = {.stop_at = 0};
	char err[512] = "", want[512];
	assert_int_equal(each(&s, err, sizeof(err)), -EILSEQ);
	assert_int_equal(s.lines, 1);
	snprintf(want, sizeof(want), "%s line 2: byte 0x00 at column 5 is no text: not a test file",
		 path);
	assert_string_equal(err, want);
	write_bytes(path, "a\tb\v\f\r\nc\x1b[0m\n", 13);
	s = (struct seen){.stop_at = 0};
	assert_int_equal(each(&s, err, sizeof(err)), -EILSEQ);
	assert_int_equal(s.lines, 1); /* tab, VT and FF are text; ESC is not */
	assert_non_null(strstr(err, "line 2: byte 0x1b at column 2"));
}

/* What is no regular file is refused before a byte is read: never a wait, never 2 GB. */
static void test_refused(void **state)
{
	(void)state;
	struct seen s = {.stop_at = 0};
	char err[512] = "", fifo[300];
	assert_int_equal(mvod_lines_each("/nonexistent/f", "test file", see, &s, err, sizeof(err)),
			 -ENOENT);
	assert_non_null(strstr(err, "cannot read /nonexistent/f"));
	assert_int_equal(mvod_lines_each(harness_tmpdir(), "test file", see, &s, err, sizeof(err)),
			 -EISDIR);
	assert_non_null(strstr(err, "is a directory: name the test file, a file"));
	snprintf(fifo, sizeof(fifo), "%s/fifo", harness_tmpdir());
	unlink(fifo);
	assert_int_equal(mkfifo(fifo, 0600), 0);
	int w = open(fifo, O_RDWR | O_CLOEXEC); /* a writer that never writes: a read would block */
	assert_true(w >= 0);
	assert_int_equal(mvod_lines_each(fifo, "test file", see, &s, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "is a FIFO: the test file must be a regular file"));
	close(w);
	assert_int_equal(mvod_lines_each("/dev/zero", "test file", see, &s, err, sizeof(err)),
			 -EINVAL);
	assert_non_null(strstr(err, "/dev/zero is a character device"));
	assert_string_equal(s.text, "");
}

/* A file read is an input: the output policy refuses it afterwards. */
static void test_noted(void **state)
{
	(void)state;
	harness_write_file(path, "1\n");
	mvod_inputs_forget();
	struct seen s = {.stop_at = 0};
	char err[512] = "", target[4096];
	assert_int_equal(mvod_output_check("--trajectory", path, target, sizeof(target), NULL, err,
					   sizeof(err)), 0);
	assert_int_equal(each(&s, err, sizeof(err)), 0);
	assert_int_equal(mvod_output_check("--trajectory", path, target, sizeof(target), NULL, err,
					   sizeof(err)), -EEXIST);
	mvod_inputs_forget();
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_lines),
		cmocka_unit_test(test_refills),
		cmocka_unit_test(test_too_long),
		cmocka_unit_test(test_not_text),
		cmocka_unit_test(test_refused),
		cmocka_unit_test(test_noted),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}

/*
 * Journal detection: stderr is the journal exactly when JOURNAL_STREAM names its device and
 * inode; then lines carry "<N>" priorities (sd-daemon.h), else the plain "mvod: level: " form.
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

#include "mvod/log.h"

/* JOURNAL_STREAM's value for fd, its device and inode numbers moved by the offsets. */
static void stream_name(int fd, unsigned dev_off, unsigned ino_off, char *env, size_t len)
{
	struct stat st;
	assert_int_equal(fstat(fd, &st), 0);
	snprintf(env, len, "%llu:%llu", (unsigned long long)st.st_dev + dev_off,
		 (unsigned long long)st.st_ino + ino_off);
}

static void test_journal_stream_detection(void **state)
{
	(void)state;
	FILE *f = tmpfile(), *g = tmpfile();
	assert_non_null(f);
	assert_non_null(g);
	char env[64];
	stream_name(fileno(f), 0, 0, env, sizeof(env));
	assert_true(mvod_log_is_journal(env, fileno(f)));
	/* Another file, no file, junk after the numbers, no variable: not the journal. */
	assert_false(mvod_log_is_journal(env, fileno(g)));
	assert_false(mvod_log_is_journal(env, -1));
	strcat(env, "x");
	assert_false(mvod_log_is_journal(env, fileno(f)));
	assert_false(mvod_log_is_journal(NULL, fileno(f)));
	assert_false(mvod_log_is_journal("", fileno(f)));
	/* Either number off by one: not the journal. */
	stream_name(fileno(f), 0, 1, env, sizeof(env));
	assert_false(mvod_log_is_journal(env, fileno(f)));
	stream_name(fileno(f), 1, 0, env, sizeof(env));
	assert_false(mvod_log_is_journal(env, fileno(f)));
	fclose(f);
	fclose(g);
}

static void emit_levels(void)
{
	mvod_log_set_level(MVOD_LOG_DEBUG);
	LOG(ERROR, "e %d", 1);
	LOG(WARN, "w");
	LOG(INFO, "i");
	LOG(DEBUG, "d");
	mvod_log_set_level(MVOD_LOG_WARN);
	LOG(INFO, "hidden");
}

static void emit_one(void)
{
	LOG(ERROR, "first");
}

/*
 * What emit() writes to stderr, with stderr a temporary file; with journal_env, JOURNAL_STREAM
 * names that file, as systemd names the journal's socket.
 */
static void capture(void (*emit)(void), bool journal_env, char *out, size_t len)
{
	fflush(stderr);
	int saved = dup(STDERR_FILENO);
	FILE *f = tmpfile();
	assert_non_null(f);
	char env[64];
	stream_name(fileno(f), 0, 0, env, sizeof(env));
	if (journal_env)
		setenv("JOURNAL_STREAM", env, 1);
	dup2(fileno(f), STDERR_FILENO);
	emit();
	fflush(stderr);
	dup2(saved, STDERR_FILENO);
	close(saved);
	rewind(f);
	size_t n = fread(out, 1, len - 1, f);
	out[n] = '\0';
	fclose(f);
}

/* Decided from the environment at the first message: a journal stream gets priorities. */
static void test_detected_at_first_message(void **state)
{
	(void)state;
	char out[512];
	capture(emit_one, true, out, sizeof(out));
	assert_string_equal(out, "<3>error: first\n");
}

static void test_line_formats(void **state)
{
	(void)state;
	char out[512];
	mvod_log_set_journal(true);
	capture(emit_levels, false, out, sizeof(out));
	assert_string_equal(out, "<3>error: e 1\n<4>warn: w\n<6>info: i\n<7>debug: d\n");
	mvod_log_set_journal(false);
	capture(emit_levels, false, out, sizeof(out));
	assert_string_equal(out, "mvod: error: e 1\nmvod: warn: w\nmvod: info: i\nmvod: debug: d\n");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		/* First, while no message has been logged yet. */
		cmocka_unit_test(test_detected_at_first_message),
		cmocka_unit_test(test_journal_stream_detection),
		cmocka_unit_test(test_line_formats),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}

/*
 * The option reference is the parser's table (issue 38): mvod --help-all and the manual page
 * mvod(1) (mvod --man, which meson installs as share/man/man1/mvod.1) list every option of
 * mvod run's parser and nothing else, each key with its default and config key. The table is
 * enumerated here through the library (mvod_config_keys, mvod_config_flags), and the parser
 * is shown to take every entry of it: one --print-config run with each key's flag at its
 * default, each other flag alone.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/config.h"

#define MAX_OPTIONS 128

static struct run_result r;

/* mvod with args (NULL-terminated); the test fails unless it exits with code. */
static void mvod(int code, ...)
{
	char *argv[MAX_OPTIONS * 2] = {(char *)harness_bin("MVOD")};
	int n = 1;
	va_list ap;
	va_start(ap, code);
	for (char *a; n < MAX_OPTIONS * 2 - 1 && (a = va_arg(ap, char *));)
		argv[n++] = a;
	va_end(ap);
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != code)
		fail_msg("%s: exit %d, not %d: %s", argv[1], r.status, code, r.err);
}

/* Every long option of the table: each key's flag, then each flag of mvod_config_flags. */
static int table(const char **names)
{
	int n = 0;
	for (int k = 0; k < mvod_config_nkeys; k++)
		names[n++] = mvod_config_keys[k].flag;
	for (int f = 0; f < MVOD_FLAG_COUNT; f++)
		names[n++] = mvod_config_flags[f].flag;
	return n;
}

/*
 * The options a reference lists, in got (each once, or the test fails): in --help-all, every
 * line "  --NAME ..." or "  -X, --NAME ..."; in roff, the line after ".TP" that starts with a
 * bold option, "\fB\-\-NAME\fR" (hyphens unescaped first).
 */
static int listed(char *text, bool roff, const char **got)
{
	int n = 0;
	bool after_tp = false;
	for (char *save, *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
		char *name = NULL;
		if (!roff && strncmp(line, "  -", 3) == 0)
			name = strstr(line, "--") + 2;
		else if (roff && after_tp && strncmp(line, "\\fB-", 4) == 0)
			name = strstr(line, "\\fB--") + 5;
		after_tp = roff && strcmp(line, ".TP") == 0;
		if (!name)
			continue;
		name[strcspn(name, roff ? "\\ " : " ")] = '\0';
		for (int i = 0; i < n; i++)
			if (strcmp(got[i], name) == 0)
				fail_msg("--%s is listed twice", name);
		assert_true(n < MAX_OPTIONS);
		got[n++] = name;
	}
	return n;
}

/* got holds exactly the table's options (both are lists without repeats). */
static void same_as_table(const char **got, int n, const char *what)
{
	const char *want[MAX_OPTIONS];
	int m = table(want);
	for (int i = 0; i < m; i++) {
		int j = 0;
		while (j < n && strcmp(got[j], want[i]) != 0)
			j++;
		if (j == n)
			fail_msg("%s does not list --%s, which the parser takes", what, want[i]);
	}
	if (n != m)
		fail_msg("%s lists %d options; the parser takes %d", what, n, m);
}

/* Each key's default and config key, as the reference writes them, is in text. */
static void facts_of_every_key(const char *text)
{
	struct mvod_config d;
	mvod_config_default(&d);
	for (int k = 0; k < mvod_config_nkeys; k++) {
		const struct mvod_config_key *key = &mvod_config_keys[k];
		char value[256], want[512];
		mvod_config_value_text(&d, k, value, sizeof(value));
		if (key->type == MVOD_CONFIG_BOOL)
			snprintf(want, sizeof(want), "Config: [%s] %s = %s (default %s).", key->section,
				 key->key, key->flag_value ? "true" : "false", value);
		else
			snprintf(want, sizeof(want), "Default: %s", key->dflt ? key->dflt
						     : *value ? value : "none");
		char config[128];
		snprintf(config, sizeof(config), "Config: [%s] %s", key->section, key->key);
		if (!strstr(text, want) || !strstr(text, config))
			fail_msg("--%s: no \"%s\" or \"%s\"", key->flag, want, config);
	}
}

/* A line-wrapped text on one line: every run of spaces and newlines as one space. */
static void unwrap(char *text)
{
	char *w = text;
	for (char *p = text; *p; p++)
		if ((*p != ' ' && *p != '\n') || (w > text && w[-1] != ' '))
			*w++ = *p == '\n' ? ' ' : *p;
	*w = '\0';
}

static void test_help_all(void **state)
{
	(void)state;
	mvod(0, "--help-all", NULL);
	static char text[sizeof(r.out)], flat[sizeof(r.out)];
	memcpy(text, r.out, sizeof(text));
	memcpy(flat, r.out, sizeof(flat));
	const char *got[MAX_OPTIONS];
	same_as_table(got, listed(text, false, got), "mvod --help-all");
	unwrap(flat);
	facts_of_every_key(flat);
	assert_non_null(strstr(r.out, "\n  -q, --quiet\n"));
	assert_non_null(strstr(r.out, "\n  -h, --help\n"));
}

/* The roff with its hyphens unescaped, in buf. */
static void man(char *buf, size_t len)
{
	mvod(0, "--man", NULL);
	size_t n = 0;
	for (const char *p = r.out; *p && n + 1 < len; p++)
		if (!(p[0] == '\\' && p[1] == '-'))
			buf[n++] = *p;
	buf[n] = '\0';
}

static void test_man_page(void **state)
{
	(void)state;
	static char text[sizeof(r.out)], flat[sizeof(r.out)];
	man(text, sizeof(text));
	memcpy(flat, text, sizeof(flat));
	assert_int_equal(strncmp(strstr(text, ".TH "), ".TH MVOD 1 ", 11), 0);
	static const char *const sections[] = {"NAME", "SYNOPSIS", "DESCRIPTION", "COMMANDS",
		"OPTIONS", "EXIT STATUS", "ENVIRONMENT", "FILES", "EXAMPLES", "SEE ALSO"};
	for (size_t i = 0; i < sizeof(sections) / sizeof(sections[0]); i++) {
		char sh[64];
		snprintf(sh, sizeof(sh), "\n.SH %s\n", sections[i]);
		if (!strstr(text, sh))
			fail_msg("mvod(1) has no %s section", sections[i]);
	}
	const char *got[MAX_OPTIONS];
	same_as_table(got, listed(text, true, got), "mvod --man");
	unwrap(flat);
	facts_of_every_key(flat);
}

/* The built (and installed) mvod.1 is what the binary prints: generated, never edited. */
static void test_man_installed(void **state)
{
	(void)state;
	size_t len;
	char *built = harness_slurp(harness_bin("MVOD_BUILDDIR"), "mvod.1", &len);
	mvod(0, "--man", NULL);
	assert_int_equal(len, strlen(r.out));
	assert_memory_equal(built, r.out, len);
	free(built);
	char root[300], cmd[700];
	snprintf(root, sizeof(root), "%s/root", harness_tmpdir());
	harness_meson_install(root);
	snprintf(cmd, sizeof(cmd), "cmp -s \"$(find %s -path '*/share/man/man1/mvod.1')\" %s/mvod.1",
		 root, harness_bin("MVOD_BUILDDIR"));
	if (system(cmd) != 0)
		fail_msg("meson install put no share/man/man1/mvod.1 equal to the built one in %s", root);
}

/*
 * The parser takes every key of the table: one run gives each key's flag its default (a
 * bool's flag alone), -q too, and --config an empty file; then each other flag on its own.
 */
static void test_parser_takes_the_table(void **state)
{
	(void)state;
	static char values[64][256];
	char *argv[MAX_OPTIONS * 2] = {(char *)harness_bin("MVOD"), "--print-config", "-q",
				       "--config", (char *)harness_tmp_path("empty.conf")};
	int n = 5;
	harness_write_file(argv[4], "");
	struct mvod_config d;
	mvod_config_default(&d);
	for (int k = 0; k < mvod_config_nkeys; k++) {
		static char flags[64][64];
		snprintf(flags[k], sizeof(flags[k]), "--%s", mvod_config_keys[k].flag);
		argv[n++] = flags[k];
		mvod_config_value_text(&d, k, values[k], sizeof(values[k]));
		if (mvod_config_keys[k].type != MVOD_CONFIG_BOOL)
			argv[n++] = values[k];
	}
	argv[n] = NULL;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0 || strncmp(r.out, "# mvod configuration", 20) != 0)
		fail_msg("exit %d: %s", r.status, r.err);
	mvod(0, "--help", NULL);
	assert_int_equal(strncmp(r.out, "Usage: mvod [run] --source URI [options]\n", 41), 0);
	/* --help stays short: a line an option; defaults and config keys are --help-all's. */
	assert_null(strstr(r.out, "Default: "));
	assert_null(strstr(r.out, "Config: ["));
	mvod(0, "-h", NULL);
	mvod(0, "--version", NULL);
	mvod(0, "--list-cameras", NULL);
	mvod(2, "--no-such-option", NULL);
	assert_non_null(strstr(r.err, "unknown or incomplete option '--no-such-option'"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_help_all),
		cmocka_unit_test(test_man_page),
		cmocka_unit_test(test_man_installed),
		cmocka_unit_test(test_parser_takes_the_table),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}

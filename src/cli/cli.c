/* Option parsing shared by the subcommands. */
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mvod/board.h"
#include "mvod/log.h"
#include "mvod/pipeline.h"
#include "util/output.h"

const char *cli_prog = "mvod";

static int append(struct option *dst, int n, const struct option *src)
{
	for (const struct option *o = src; o && o->name && n < CLI_MAX_OPTIONS - 1; o++)
		dst[n++] = *o;
	return n;
}

/* The flags of mvod_config_flags that every command takes (every) or mvod run's own. */
static int append_flags(struct option *dst, int n, bool every, int base)
{
	for (int f = 0; f < MVOD_FLAG_COUNT && n < CLI_MAX_OPTIONS - 1; f++) {
		const struct mvod_config_flag *c = &mvod_config_flags[f];
		if (c->every_command == every)
			dst[n++] = (struct option){c->flag, c->arg ? required_argument : no_argument,
						   NULL, c->short_flag ? c->short_flag : base + f};
	}
	return n;
}

void cli_run_flags(struct option *dst)
{
	dst[append_flags(dst, 0, false, CLI_OPT_OWN)] = (struct option){0};
}

static bool is_general_key(const struct mvod_config_key *k)
{
	return strcmp(k->section, "log") == 0;
}

void cli_options_join(struct option *dst, bool with_run, const struct option *own)
{
	int n = append_flags(dst, 0, true, CLI_OPT_FLAG);
	for (int k = 0; k < mvod_config_nkeys && n < CLI_MAX_OPTIONS - 1; k++) {
		const struct mvod_config_key *key = &mvod_config_keys[k];
		if (with_run || is_general_key(key))
			dst[n++] = (struct option){key->flag,
						   key->type == MVOD_CONFIG_BOOL ? no_argument
										 : required_argument,
						   NULL, CLI_OPT_KEY + k};
	}
	n = append(dst, n, own);
	dst[n] = (struct option){0};
}

int cli_bad_value(const char *opt, const char *val, const char *want)
{
	fprintf(stderr, "%s: --%s %s: expected %s\n", cli_prog, opt, val, want);
	return -EINVAL;
}

int cli_parse_double(const char *opt, const char *s, double lo, double hi, double *out)
{
	char *end;
	errno = 0;
	double v = strtod(s, &end);
	if (errno || end == s || *end || !isfinite(v) || v < lo || v > hi) {
		char want[96];
		snprintf(want, sizeof(want), "a number in [%g, %g]", lo, hi);
		return cli_bad_value(opt, s, want);
	}
	*out = v;
	return 0;
}

int cli_parse_int(const char *opt, const char *s, long lo, long hi, long *out)
{
	char *end;
	errno = 0;
	long v = strtol(s, &end, 10);
	if (errno || end == s || *end || v < lo || v > hi) {
		char want[96];
		snprintf(want, sizeof(want), "an integer in [%ld, %ld]", lo, hi);
		return cli_bad_value(opt, s, want);
	}
	*out = v;
	return 0;
}

bool cli_has_suffix(const char *s, const char *suffix)
{
	size_t n = strlen(s), m = strlen(suffix);
	return n >= m && strcmp(s + n - m, suffix) == 0;
}

int cli_parse_board(const char *s, struct mvod_board *b)
{
	char why[256];
	if (mvod_board_parse(s, b, why, sizeof(why)) == 0)
		return 0;
	fprintf(stderr, "%s: --board %s: %s\n", cli_prog, s, why);
	return -EINVAL;
}

int cli_check_writable(const char *opt, const char *path)
{
	char target[4096], err[MVOD_ERR_MAX];
	int ret = mvod_output_check(opt, path, target, sizeof(target), NULL, err, sizeof(err));
	if (ret)
		fprintf(stderr, "%s: %s\n", cli_prog, err);
	return ret;
}

int cli_run_status(int ret, const struct mvod_run_summary *s)
{
	if (!ret)
		return EXIT_SUCCESS;
	/* An unknown scheme is the URI's fault, as everything the run found before a frame. */
	return s->config_failed || ret == -EPROTONOSUPPORT ? EXIT_USAGE : EXIT_FAILURE;
}

int cli_check_frontend(const struct mvod_config *cfg)
{
	char err[256];
	if (!mvod_config_check_frontend(&cfg->run.vo, err, sizeof(err)))
		return 0;
	fprintf(stderr, "%s: %s; see %s --help\n", cli_prog, err, cli_prog);
	return -EINVAL;
}

int cli_parse_key(int k, const char *arg, struct mvod_config *cfg)
{
	char want[256];
	if (mvod_config_set(cfg, k, arg, want, sizeof(want)) == 0)
		return 0;
	return cli_bad_value(mvod_config_keys[k].flag, arg, want);
}

/* getopt's short options: the tables' letters (-q, -h). */
static void short_options(char *buf, size_t len)
{
	size_t n = 0;
	for (int k = 0; k < mvod_config_nkeys && n + 1 < len; k++)
		if (mvod_config_keys[k].short_flag)
			buf[n++] = mvod_config_keys[k].short_flag;
	for (int f = 0; f < MVOD_FLAG_COUNT && n + 1 < len; f++)
		if (mvod_config_flags[f].short_flag && mvod_config_flags[f].every_command)
			buf[n++] = mvod_config_flags[f].short_flag;
	buf[n] = '\0';
}

/* Short options are the table's short flags (-q); getopt hands back the letter. */
static int short_key(int id)
{
	for (int k = 0; k < mvod_config_nkeys; k++)
		if (mvod_config_keys[k].short_flag && mvod_config_keys[k].short_flag == id)
			return k;
	return -1;
}

static int parse_option(int id, const char *arg, cli_own_parse_fn own_parse, void *ctx,
			struct mvod_config *cfg)
{
	if (id >= CLI_OPT_OWN && own_parse)
		return own_parse(id, arg, ctx);
	int k = id >= CLI_OPT_KEY && id < CLI_OPT_KEY + mvod_config_nkeys ? id - CLI_OPT_KEY
									    : short_key(id);
	return k >= 0 ? cli_parse_key(k, arg, cfg) : -ENOENT;
}

int cli_getopt_args(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
		    void *ctx, void (*usage)(FILE *), struct mvod_config *cfg, int *quiet,
		    const char **args, int nargs, const char *args_usage)
{
	struct option opts[CLI_MAX_OPTIONS];
	cli_options_join(opts, cfg != NULL, own);
	char shorts[16];
	short_options(shorts, sizeof(shorts));
	struct mvod_config general;
	mvod_config_default(&general);
	struct mvod_config *c = cfg ? cfg : &general;
	int id;
	opterr = 0;
	optind = 1;
	while ((id = getopt_long(argc, argv, shorts, opts, NULL)) != -1) {
		if (id == mvod_config_flags[MVOD_FLAG_HELP].short_flag) {
			usage(stdout);
			return 1;
		}
		if (id == CLI_OPT_FLAG + MVOD_FLAG_VERSION) {
			printf("mvod %s\n", MVOD_VERSION);
			return 1;
		}
		if (id == '?') {
			fprintf(stderr, "%s: unknown or incomplete option '%s'; see %s --help\n",
				cli_prog, argv[optind - 1], cli_prog);
			return -EINVAL;
		}
		int ret = parse_option(id, optarg, own_parse, ctx, c);
		if (ret == -ENOENT) {
			fprintf(stderr, "%s: option '%s' does not apply here; see %s --help\n",
				cli_prog, argv[optind - 1], cli_prog);
			return -EINVAL;
		}
		if (ret)
			return -EINVAL;
	}
	/* GNU getopt has moved the operands behind the options, wherever the user put them. */
	if (argc - optind != nargs) {
		if (nargs)
			fprintf(stderr, "%s: expected %s; see %s --help\n", cli_prog, args_usage,
				cli_prog);
		else
			fprintf(stderr, "%s: unexpected argument '%s'; see %s --help\n", cli_prog,
				argv[optind], cli_prog);
		return -EINVAL;
	}
	for (int i = 0; i < nargs; i++)
		args[i] = argv[optind + i];
	if (!cfg)
		mvod_config_apply_log(&general);
	if (quiet)
		*quiet = c->quiet;
	return 0;
}

int cli_getopt(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
	       void *ctx, void (*usage)(FILE *), struct mvod_config *cfg, int *quiet)
{
	return cli_getopt_args(argc, argv, own, own_parse, ctx, usage, cfg, quiet, NULL, 0, NULL);
}

/*
 * FFmpeg and libcamera print their own diagnostics (a corrupt file, every camera probed) before
 * mvod can say which source and what to do; keep them for --log-level debug. A value the user
 * exported wins.
 */
void cli_quiet_libraries(void)
{
	if (mvod_log_get_level() >= MVOD_LOG_DEBUG)
		return;
	setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0); /* AV_LOG_QUIET */
	setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
}

static volatile sig_atomic_t stop_reading;

static void on_stop(int sig)
{
	(void)sig;
	stop_reading = 1;
}

volatile sig_atomic_t *cli_stop_on_interrupt(void)
{
	struct sigaction sa = {.sa_handler = on_stop, .sa_flags = SA_RESETHAND};
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	return &stop_reading;
}

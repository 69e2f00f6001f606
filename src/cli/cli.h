/*
 * What the subcommands share: value parsers that name the option in their message, and the
 * input and visual-odometry options common to `mvod run` and `mvod bench`.
 */
#ifndef MVOD_CLI_H
#define MVOD_CLI_H

#include <getopt.h>
#include <stdbool.h>
#include <stdio.h>

#include "mvod/pipeline.h"

#define EXIT_USAGE 2

/* Prints "mvod CMD: --opt val: expected want" and returns -EINVAL. */
int cli_bad_value(const char *opt, const char *val, const char *want);
int cli_parse_double(const char *opt, const char *s, double lo, double hi, double *out);
int cli_parse_int(const char *opt, const char *s, long lo, long hi, long *out);
bool cli_has_suffix(const char *s, const char *suffix);
/* Parses a board spec, printing the parser's reason on failure (-EINVAL). */
struct mvod_board;
int cli_parse_board(const char *s, struct mvod_board *b);
/*
 * Whether --opt FILE can be written, before any work: its directory must be writable and FILE
 * not a directory. Prints the reason and returns -errno when not.
 */
int cli_check_writable(const char *opt, const char *path);

/* Leaves FFmpeg's and libcamera's own diagnostics for --log-level debug: mvod says what to do. */
void cli_quiet_libraries(void);

/* The subcommand's name for messages ("mvod", "mvod calibrate", ...). */
extern const char *cli_prog;

/* Option ids of the shared groups; each command numbers its own from CLI_OPT_OWN. */
enum cli_opt_id {
	CLI_OPT_SOURCE = 256, CLI_OPT_CALIB, CLI_OPT_GT, CLI_OPT_MAX_FRAMES,
	CLI_OPT_SCALE, CLI_OPT_DETECTOR, CLI_OPT_MATCHER, CLI_OPT_FEATURES, CLI_OPT_RATIO,
	CLI_OPT_BEST, CLI_OPT_ROBUST,
	CLI_OPT_RANSAC_PX, CLI_OPT_CONFIDENCE, CLI_OPT_MIN_PARALLAX, CLI_OPT_RESIZE, CLI_OPT_BLUR,
	CLI_OPT_LOG_LEVEL, CLI_OPT_VERSION,
	CLI_OPT_OWN = 512,
};

/*
 * Copies into dst the options of every command (--log-level -q -h --version), with_run the
 * input and VO options (--source --calib --gt --max-frames --scale --features ...), and a
 * command's own (terminated by a zero entry).
 */
#define CLI_MAX_OPTIONS 64
void cli_options_join(struct option *dst, bool with_run, const struct option *own);

/* Usage text of the shared groups. */
void cli_usage_input(FILE *out);
void cli_usage_vo(FILE *out);
void cli_usage_general(FILE *out);

/*
 * Applies a shared option to o. Returns 0 when taken, -EINVAL on a bad value (already
 * reported), -ENOENT when id is not a shared option.
 */
int cli_parse_shared(int id, const char *arg, struct mvod_run_opts *o, int *quiet);

/*
 * The common getopt loop. own_parse handles the command's own ids (return 0 or -EINVAL). o
 * receives the input and VO options; NULL for commands that take none (calibrate, board).
 * Returns 0 to go on, 1 after --help/--version, -EINVAL on a usage error (reported).
 */
typedef int (*cli_own_parse_fn)(int id, const char *arg, void *ctx);
int cli_getopt(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
	       void *ctx, void (*usage)(FILE *), struct mvod_run_opts *o, int *quiet);
/*
 * The same for a command that takes exactly nargs operands (anywhere among the options): they
 * land in args[0..nargs-1]; a different count is a usage error naming args_usage ("IN and OUT").
 */
int cli_getopt_args(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
		    void *ctx, void (*usage)(FILE *), struct mvod_run_opts *o, int *quiet,
		    const char **args, int nargs, const char *args_usage);

/* Subcommands: argv[0] is the subcommand's name. Return the process exit status. */
int mvod_cmd_run(int argc, char **argv);
int mvod_cmd_calibrate(int argc, char **argv);
int mvod_cmd_board(int argc, char **argv);
int mvod_cmd_convert(int argc, char **argv);
int mvod_cmd_view(int argc, char **argv);
int mvod_cmd_bench(int argc, char **argv);

#endif

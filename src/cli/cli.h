/*
 * What the subcommands share: value parsers that name the option in their message, and the
 * input and visual-odometry options common to `mvod run` and `mvod bench`.
 */
#ifndef MVOD_CLI_H
#define MVOD_CLI_H

#include <getopt.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>

#include "mvod/config.h"
#include "util/errbuf.h"

/*
 * Exit status by cause, the same for every command: 0 success; EXIT_FAILURE (1) a run-time
 * fault, which a restart may fix (a camera absent at boot, a write that failed, a source that
 * broke off); EXIT_USAGE (2) a usage or configuration error, which only an edit fixes (a bad
 * flag or config file; a calibration, ground truth or --scale source that cannot serve; an
 * output the policy refuses at start). mvod.service does not restart on 2
 * (RestartPreventExitStatus=2), so a bad configuration stops it instead of a restart every
 * 5 s.
 */
#define EXIT_USAGE 2

/* The exit status of mvod_run's ret and summary (mvod run, mvod bench), by the cause above. */
struct mvod_run_summary;
int cli_run_status(int ret, const struct mvod_run_summary *s);

/* Prints "mvod CMD: --opt val: expected want" and returns -EINVAL. */
int cli_bad_value(const char *opt, const char *val, const char *want);
int cli_parse_double(const char *opt, const char *s, double lo, double hi, double *out);
int cli_parse_int(const char *opt, const char *s, long lo, long hi, long *out);
bool cli_has_suffix(const char *s, const char *suffix);
/* Parses a board spec, printing the parser's reason on failure (-EINVAL). */
struct mvod_board;
int cli_parse_board(const char *s, struct mvod_board *b);
/*
 * Whether FILE, given as opt ("--out", "OUT"), can be written, before any work, by the output policy (util/output.h):
 * not a directory, block device, socket or input noted so far, in a folder that can be written
 * in. Prints the reason and returns -errno when not.
 */
/* mvod run's SIGINT, SIGTERM (stop) and SIGHUP (reopen) handlers; idempotent. */
void cli_run_install_signals(void);

int cli_check_writable(const char *opt, const char *path);

/*
 * A live camera never ends: the first SIGINT or SIGTERM sets the flag returned (reading stops
 * and the command works on what it read); SA_RESETHAND lets a second one abort as usual.
 */
volatile sig_atomic_t *cli_stop_on_interrupt(void);

/* Leaves FFmpeg's and libcamera's own diagnostics for --log-level debug: mvod says what to do. */
void cli_quiet_libraries(void);

/* The subcommand's name for messages ("mvod", "mvod calibrate", ...). */
extern const char *cli_prog;

/*
 * Option ids: mvod_config_keys[k] is CLI_OPT_KEY + k (the flags of the config table), the
 * flags every command takes CLI_OPT_FLAG + their enum mvod_config_flag_id (or their short
 * letter, -h); each command numbers its own from CLI_OPT_OWN.
 */
enum cli_opt_id {
	CLI_OPT_FLAG = 240,
	CLI_OPT_KEY = 256,
	CLI_OPT_OWN = 512,
};

/*
 * Copies into dst the options of every command (--log-level -q -h --version), with_run every
 * other flag of the config table (--source --calib ... --trajectory --lcm-url ...), and a
 * command's own (terminated by a zero entry).
 */
#define CLI_MAX_OPTIONS 80
void cli_options_join(struct option *dst, bool with_run, const struct option *own);
/*
 * mvod run's own flags of mvod_config_flags (--config, --print-config, --list-cameras,
 * --help-all, --man), as CLI_OPT_OWN + their enum mvod_config_flag_id, into dst (room for
 * MVOD_FLAG_COUNT + 1), terminated by a zero entry.
 */
void cli_run_flags(struct option *dst);

/*
 * The option reference, from the tables the parser uses (mvod_config_keys, mvod_config_flags,
 * cli_commands): help.c. Which options a text lists: mvod run's (all), mvod bench's (the
 * table's keys but mvod run's own and LCM's), or the General group every command has.
 */
enum cli_scope { CLI_SCOPE_RUN, CLI_SCOPE_BENCH, CLI_SCOPE_GENERAL };
/* "Usage: mvod COMMAND ARGS" of cli_commands, "mvod [run] ..." for run. */
void cli_usage_synopsis(FILE *out, const char *command);
/* The scope's options, grouped, one line each (--help). */
void cli_usage_options(FILE *out, enum cli_scope scope);
/* The General group: --log-level, -q, -h, --version. */
void cli_usage_general(FILE *out);
/* mvod run's --help, --help-all (every option: value, default, config key, description). */
void cli_usage_run(FILE *out);
void cli_help_all(FILE *out);
/* mvod(1) as roff: mvod run's options as --help-all has them, and every command. */
void cli_man(FILE *out);

/* --frontend klt with a descriptor option: -EINVAL after saying which (mvod_vo_check_frontend). */
int cli_check_frontend(const struct mvod_config *cfg);

/*
 * Sets config key k from a flag's argument (NULL for a flag without one). Returns 0, or
 * -EINVAL after printing "--flag VALUE: expected ...".
 */
int cli_parse_key(int k, const char *arg, struct mvod_config *cfg);

/*
 * The common getopt loop. own_parse handles the command's own ids (return 0 or -EINVAL). cfg
 * receives the config table's flags, marked as given in cfg->set, for the caller to lay over
 * a config file and to apply [log]; NULL for commands without run options (calibrate, board),
 * whose --log-level and -q take effect here and land in *quiet.
 * Returns 0 to go on, 1 after --help/--version, -EINVAL on a usage error (reported).
 */
typedef int (*cli_own_parse_fn)(int id, const char *arg, void *ctx);
int cli_getopt(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
	       void *ctx, void (*usage)(FILE *), struct mvod_config *cfg, int *quiet);
/*
 * The same for a command that takes exactly nargs operands (anywhere among the options): they
 * land in args[0..nargs-1]; a different count is a usage error naming args_usage ("IN and OUT").
 */
int cli_getopt_args(int argc, char **argv, const struct option *own, cli_own_parse_fn own_parse,
		    void *ctx, void (*usage)(FILE *), struct mvod_config *cfg, int *quiet,
		    const char **args, int nargs, const char *args_usage);

/* The commands, in the order --help and mvod(1) list them. */
enum cli_command_id {
	CLI_CMD_RUN,
	CLI_CMD_CALIBRATE,
	CLI_CMD_MOUNT,
	CLI_CMD_BOARD,
	CLI_CMD_CONVERT,
	CLI_CMD_BENCH,
	CLI_CMD_VIEW,
	CLI_CMD_SPEED_LOG,
	CLI_CMD_COUNT,
};
/* A command's name, what follows it in its synopsis, and its purpose. */
struct cli_command {
	const char *name, *args, *purpose;
};
/* By enum cli_command_id (help.c): main.c dispatches by name, --help and mvod(1) list them. */
extern const struct cli_command cli_commands[CLI_CMD_COUNT];

/* Subcommands: argv[0] is the subcommand's name. Return the process exit status. */
int mvod_cmd_run(int argc, char **argv);
int mvod_cmd_calibrate(int argc, char **argv);
int mvod_cmd_board(int argc, char **argv);
int mvod_cmd_convert(int argc, char **argv);
int mvod_cmd_view(int argc, char **argv);
int mvod_cmd_bench(int argc, char **argv);
int mvod_cmd_mount(int argc, char **argv);
int mvod_cmd_speed_log(int argc, char **argv);

#endif

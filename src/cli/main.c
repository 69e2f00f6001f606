/* mvod: picks the subcommand; `mvod --source ...` without one means `mvod run`. */
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

struct command {
	const char *name;
	int (*main)(int argc, char **argv);
};

static const struct command commands[] = {
	{"run", mvod_cmd_run},
	{"calibrate", mvod_cmd_calibrate},
	{"mount", mvod_cmd_mount},
	{"board", mvod_cmd_board},
	{"calib-convert", mvod_cmd_convert},
	{"view", mvod_cmd_view},
	{"bench", mvod_cmd_bench},
	{"speed-log", mvod_cmd_speed_log},
};

/*
 * glibc runs an executable's .preinit_array with main's arguments before any shared library's
 * initialiser (OpenCV's, Ceres's): mvod run's handlers are in place before that work, not after
 * it and the start of main (0.2 s of CPU, over a second of wall time on a busy machine,
 * measured with `time mvod --version`), so that a SIGHUP sent as the daemon starts does not
 * kill it. Other commands keep the default actions, as interactive tools should.
 */
static void early_signals(int argc, char **argv, char **envp)
{
	(void)envp;
	if (argc < 2 || argv[1][0] == '-' || strcmp(argv[1], "run") == 0)
		cli_run_install_signals();
}
__attribute__((section(".preinit_array"), used)) static void (*const preinit)(int, char **,
									     char **) = early_signals;

int main(int argc, char **argv)
{
	/*
	 * A reader that goes away (an output on a pipe or FIFO, a socket under LCM) must be a write
	 * error the command reports, not a signal that kills it without a word; for every command.
	 */
	struct sigaction ign = {.sa_handler = SIG_IGN};
	sigaction(SIGPIPE, &ign, NULL);
	if (argc > 1 && argv[1][0] != '-') {
		for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++) {
			if (strcmp(argv[1], commands[i].name) == 0) {
				static char prog[64];
				snprintf(prog, sizeof(prog), "mvod %s", commands[i].name);
				cli_prog = prog;
				return commands[i].main(argc - 1, argv + 1);
			}
		}
		fprintf(stderr, "mvod: unknown command '%s'; the commands are", argv[1]);
		for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
			fprintf(stderr, "%s %s", i ? "," : "", commands[i].name);
		fprintf(stderr, " (see mvod --help)\n");
		return EXIT_USAGE;
	}
	return mvod_cmd_run(argc, argv);
}

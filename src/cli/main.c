/* mvod: picks the subcommand; `mvod --source ...` without one means `mvod run`. */
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

/* Each command's entry point (their names and texts: cli_commands, help.c). */
static int (*const command_main[CLI_CMD_COUNT])(int argc, char **argv) = {
	[CLI_CMD_RUN] = mvod_cmd_run,
	[CLI_CMD_CALIBRATE] = mvod_cmd_calibrate,
	[CLI_CMD_MOUNT] = mvod_cmd_mount,
	[CLI_CMD_BOARD] = mvod_cmd_board,
	[CLI_CMD_CONVERT] = mvod_cmd_convert,
	[CLI_CMD_BENCH] = mvod_cmd_bench,
	[CLI_CMD_VIEW] = mvod_cmd_view,
	[CLI_CMD_SPEED_LOG] = mvod_cmd_speed_log,
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
		for (int i = 0; i < CLI_CMD_COUNT; i++) {
			if (strcmp(argv[1], cli_commands[i].name) == 0) {
				static char prog[64];
				snprintf(prog, sizeof(prog), "mvod %s", cli_commands[i].name);
				cli_prog = prog;
				return command_main[i](argc - 1, argv + 1);
			}
		}
		fprintf(stderr, "mvod: unknown command '%s'; the commands are", argv[1]);
		for (int i = 0; i < CLI_CMD_COUNT; i++)
			fprintf(stderr, "%s %s", i ? "," : "", cli_commands[i].name);
		fprintf(stderr, " (see mvod --help)\n");
		return EXIT_USAGE;
	}
	return mvod_cmd_run(argc, argv);
}

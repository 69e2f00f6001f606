/* mvod run: its command line and the run loop's setup and teardown. */
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "mvod/capture.h"
#include "mvod/ipc.h"
#include "mvod/log.h"
#include "mvod/pipeline.h"
#include "util/notify.h"
#include "util/output.h"

static volatile sig_atomic_t stop_requested, reopen_requested, running;

/*
 * The first SIGINT or SIGTERM asks for a clean stop: the frame in hand is finished, outputs
 * flushed and closed, a last status published. A second one ends mvod at once; that leaves
 * nothing partial in the trajectory, whose every line is a single write(2). Before the frame
 * loop runs and while no output is open (start-up: the configuration, a calibration, a ground
 * truth or a source that takes long to read, a FIFO that never delivers), there is nothing
 * to finish or close: the signal's own action ends mvod at once (it waited for the work to
 * end, 13 minutes for one YAML file, and systemd's stop timed out).
 */
static void on_stop(int sig)
{
	if (stop_requested)
		_exit(128 + sig);
	if (!running && !mvod_outputs_open()) {
		signal(sig, SIG_DFL);
		raise(sig);
		return;
	}
	stop_requested = 1;
}

/* The frame loop turns: from now on a stop is a clean one. A sink of mvod run's own. */
static void loop_runs(void *ctx, bool reopen)
{
	(void)ctx;
	(void)reopen;
	running = 1;
}

static const struct mvod_sink_ops running_ops = {.name = "running", .between = loop_runs};

static void on_hup(int sig)
{
	(void)sig;
	reopen_requested = 1;
}

void cli_run_install_signals(void)
{
	/* No SA_RESTART for a stop: a blocking wait returns at once to look at the flag. */
	struct sigaction stop = {.sa_handler = on_stop};
	sigaction(SIGINT, &stop, NULL);
	sigaction(SIGTERM, &stop, NULL);
	struct sigaction hup = {.sa_handler = on_hup, .sa_flags = SA_RESTART};
	sigaction(SIGHUP, &hup, NULL);
}

struct cli {
	struct mvod_config flags; /* what the command line said */
	const char *config;       /* --config FILE */
	int print_config, list_cameras;
	void (*reference)(FILE *out); /* --help-all or --man: printed, and nothing else done */
};

/* mvod run's own flags (mvod_config_flags), as CLI_OPT_OWN + their id. */
static int parse_own(int id, const char *arg, void *ctx)
{
	struct cli *c = ctx;
	switch (id - CLI_OPT_OWN) {
	case MVOD_FLAG_CONFIG: c->config = arg; return 0;
	case MVOD_FLAG_PRINT_CONFIG: c->print_config = 1; return 0;
	case MVOD_FLAG_LIST_CAMERAS: c->list_cameras = 1; return 0;
	case MVOD_FLAG_HELP_ALL: c->reference = cli_help_all; return 0;
	case MVOD_FLAG_MAN: c->reference = cli_man; return 0;
	}
	return -ENOENT;
}

/* The config file when there is one, the flags over it. -EINVAL after saying what is wrong. */
static int load_config(struct cli *c, struct mvod_config *cfg)
{
	char err[MVOD_ERR_MAX];
	mvod_config_default(cfg);
	if (c->config && mvod_config_load(c->config, cfg, err, sizeof(err))) {
		fprintf(stderr, "%s: --config: %s\n", cli_prog, err);
		return -EINVAL;
	}
	mvod_config_override(cfg, &c->flags);
	mvod_config_finish(cfg);
	mvod_config_apply_log(cfg);
	return cli_check_frontend(cfg);
}

/* 0 to run, 1 when help/version was printed, -EINVAL on a usage error. */
static int parse_cli(int argc, char **argv, struct cli *c, struct mvod_config *cfg)
{
	mvod_config_default(&c->flags);
	struct option own[MVOD_FLAG_COUNT + 1];
	cli_run_flags(own);
	int ret = cli_getopt(argc, argv, own, parse_own, c, cli_usage_run, &c->flags, NULL);
	if (!ret && c->reference) { /* before the config file: the manual needs none */
		c->reference(stdout);
		return 1;
	}
	if (!ret)
		ret = load_config(c, cfg);
	if (ret || c->list_cameras || c->print_config)
		return ret;
	if (!cfg->run.source) {
		fprintf(stderr, "mvod: --source URI is required, e.g. --source file:video.mkv (or "
				"[source] uri in the --config file); see mvod --help\n");
		return -EINVAL;
	}
	return 0;
}

/* "; 3 skipped: 2 corrupt or not an image, 1 of another size" for the frames line. */
static void print_skipped(const struct mvod_run_summary *s)
{
	int64_t all = 0;
	for (int k = 0; k < MVOD_BAD_COUNT; k++)
		all += s->skipped[k];
	if (!all)
		return;
	printf(", %lld skipped:", (long long)all);
	const char *sep = " ";
	for (int k = 0; k < MVOD_BAD_COUNT; k++) {
		if (!s->skipped[k])
			continue;
		printf("%s%lld %s", sep, (long long)s->skipped[k], mvod_bad_frame_name(k));
		sep = ", ";
	}
}

/* Accuracy, or why there is none: never a number that an alignment made up. */
static void print_accuracy(const struct mvod_config *c, const struct mvod_run_summary *s)
{
	bool metric = mvod_scale_mode_metric(c->run.vo.scale_mode);
	const char *unit = metric ? "m" : "units (free scale)";
	if (s->gt_frames < s->frames)
		printf("mvod: ground truth covers frames %lld-%lld of %lld (%lld have a pose): the "
		       "accuracy below is over those only\n", (long long)s->gt_first,
		       (long long)s->gt_last, (long long)s->frames, (long long)s->gt_frames);
	if (s->gt_static) {
		printf("mvod: accuracy vs ground truth: the ground truth does not move, but the "
		       "estimate went %.3f %s, and ended up at most %.3f from the start: no ATE\n",
		       s->est_len, unit, s->est_extent);
		return;
	}
	printf("mvod: accuracy vs ground truth: rotation error %.3f deg/frame (max %.3f), "
	       "direction error %.2f deg/frame (max %.2f), err_avg %.3f (max %.3f), ",
	       s->rpe.rot_deg_mean, s->rpe.rot_deg_max, s->rpe.dir_deg_mean, s->rpe.dir_deg_max,
	       s->rpe.err_avg, s->rpe.err_max);
	if (isnan(s->ate_rmse_m) && s->gt_frames < 3)
		printf("ATE n/a (an alignment needs 3 frames with ground truth)\n");
	else if (isnan(s->ate_rmse_m))
		printf("ATE n/a (the estimate does not move, while the ground truth goes %.1f m)\n",
		       s->path_len_m);
	else
		printf("ATE %.3f m over %.1f m, %.1f %% (%s)\n", s->ate_rmse_m, s->path_len_m,
		       100.0 * s->ate_rmse_m / fmax(s->path_len_m, 1e-9),
		       metric ? "SE(3)-aligned, no scale alignment" : "Sim(3)-aligned");
}

static void print_summary(const struct mvod_config *c, const struct mvod_run_summary *s)
{
	printf("mvod: %lld frames in %.2f s (%.1f fps), %lld tracked, %lld held, front end %s",
	       (long long)s->frames, s->wall_s, s->fps, (long long)s->tracked, (long long)s->held,
	       s->frontend);
	if (s->live)
		printf(", %lld dropped", (long long)s->dropped);
	print_skipped(s);
	printf("\n");
	printf("mvod: ms per frame, mean (max):");
	for (int k = 0; k < MVOD_STAGE_COUNT; k++)
		printf(" %s %.2f (%.1f)", mvod_stage_names[k], s->stage_ms_mean[k], s->stage_ms_max[k]);
	printf("\nmvod: frame time median %.1f ms, 95th percentile %.1f ms\n", s->frame_ms_median,
	       s->frame_ms_p95);
	if (s->have_gt)
		print_accuracy(c, s);
}

static int print_config(const struct mvod_config *cfg)
{
	char err[256];
	if (mvod_config_print(cfg, stdout, err, sizeof(err)) == 0)
		return EXIT_SUCCESS;
	fprintf(stderr, "%s: --print-config: %s\n", cli_prog, err);
	return EXIT_USAGE;
}

static int run(struct mvod_config *cfg)
{
	mvod_notify_init();
	struct mvod_ipc *ipc = NULL;
	if (cfg->lcm_enabled &&
	    mvod_ipc_create(cfg->lcm_url, cfg->pose_channel, cfg->status_channel, &ipc)) {
		LOG(ERROR, "cannot open LCM at %s: check --lcm-url (e.g. memq://, "
			   "udpm://239.255.76.67:7667?ttl=0, file:///tmp/log?mode=w)",
		    cfg->lcm_url ? cfg->lcm_url : "the default URL");
		return EXIT_FAILURE;
	}
	cfg->run.reopen = &reopen_requested;
	/* --scale external reads speed where mvod publishes unless told otherwise. */
	if (!cfg->run.speed_url && cfg->lcm_enabled)
		cfg->run.speed_url = cfg->lcm_url ? cfg->lcm_url : "";
	struct mvod_sink mark = {&running_ops, NULL};
	cfg->run.sinks = &mark;
	cfg->run.n_sinks = 1;
	struct mvod_run_summary sum;
	int ret = mvod_run(&cfg->run, ipc, &stop_requested, &sum);
	mvod_ipc_destroy(ipc);
	if (!cfg->quiet && !ret)
		print_summary(cfg, &sum);
	if (ret && sum.calib_failed) /* systemctl status shows it beside "status=2" */
		mvod_notify_status(true, "stopped: the calibration %s is unusable (see the log): "
					 "fix [calibration] file, then restart",
				   cfg->run.calib ? cfg->run.calib : "(none given)");
	else if (ret && sum.config_failed)
		mvod_notify_status(true, "stopped: the configuration cannot run (see the log): "
					 "fix it, then restart");
	return cli_run_status(ret, &sum);
}

int mvod_cmd_run(int argc, char **argv)
{
	/*
	 * First of all (again, as main's preinit did): a SIGHUP (log rotation) or SIGTERM while the
	 * configuration, libraries and source load must not kill mvod by its default action.
	 */
	cli_run_install_signals();
	struct cli c = {0};
	struct mvod_config cfg;
	mvod_config_default(&cfg);
	int ret = parse_cli(argc, argv, &c, &cfg);
	if (ret) {
		ret = ret > 0 ? EXIT_SUCCESS : EXIT_USAGE;
	} else if (c.print_config) {
		ret = print_config(&cfg);
	} else {
		cli_quiet_libraries();
		if (c.list_cameras)
			mvod_capture_list_cameras(stdout);
		ret = c.list_cameras ? EXIT_SUCCESS : run(&cfg);
	}
	mvod_config_fini(&cfg);
	mvod_config_fini(&c.flags);
	return ret;
}
